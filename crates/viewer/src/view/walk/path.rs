//! `--walk-path PATH.json`: a scripted walk for tests and benchmarks, `{"start": [x, y, z], "waypoints": [[x, y],
//! ...]}` in the file's coordinates, with `x, y` on the floor plane of the model's up axis (the up axis's frame
//! `(e1, e2)`: for a Z-up model, plan coordinates). The walker starts at `start` (dropped onto the floor below
//! it) and walks to each waypoint in turn, at walking speed; a waypoint it cannot reach (blocked for
//! `GIVE_UP_S`) is given up.
use std::path::Path;

use anyhow::{bail, Context, Result};
use glam::{DVec3, Vec3};
use hrtao_core::camera::UpAxis;
use serde::Deserialize;

/// Seconds of being blocked after which a waypoint is given up.
pub const GIVE_UP_S: f32 = 2.0;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WalkPathFile {
    pub start: [f64; 3],
    pub waypoints: Vec<[f64; 2]>,
}

impl WalkPathFile {
    pub fn read(path: &Path) -> Result<WalkPathFile> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("--walk-path {}", path.display()))?;
        let p: WalkPathFile =
            serde_json::from_str(&text).with_context(|| format!("--walk-path {}", path.display()))?;
        let finite =
            p.start.iter().all(|v| v.is_finite()) && p.waypoints.iter().flatten().all(|v| v.is_finite());
        if !finite {
            bail!(
                "--walk-path {}: every coordinate must be a finite number",
                path.display()
            );
        }
        Ok(p)
    }
}

/// A walk along the path in the scene's coordinates.
#[derive(Clone, Debug)]
pub struct WalkPath {
    pub start: Vec3,
    /// The waypoints still ahead, in the scene's coordinates at the start's height (only their horizontal part
    /// counts).
    ahead: std::collections::VecDeque<Vec3>,
    blocked_s: f32,
    up: UpAxis,
    pub given_up: u32,
    pub reached: u32,
}

impl WalkPath {
    /// The path of `file` in a scene whose coordinates start at `origin` in the file's.
    pub fn new(file: &WalkPathFile, origin: [f64; 3], up: UpAxis) -> WalkPath {
        let o = DVec3::from(origin);
        let start = (DVec3::from(file.start) - o).as_vec3();
        let height = up.to_frame(DVec3::from(file.start)).z;
        let ahead = file
            .waypoints
            .iter()
            .map(|&[a, b]| (up.from_frame(DVec3::new(a, b, height)) - o).as_vec3())
            .collect();
        WalkPath {
            start,
            ahead,
            blocked_s: 0.0,
            up,
            given_up: 0,
            reached: 0,
        }
    }

    /// Where to look and walk from `feet` this frame (None: the path is done), given that the last step was
    /// blocked or not over `dt` seconds. A waypoint within `reach` (horizontally) is reached.
    pub fn heading(&mut self, feet: Vec3, blocked: bool, dt: f32, reach: f32) -> Option<Vec3> {
        let up = self.up.vector();
        loop {
            let target = *self.ahead.front()?;
            let d = target - feet;
            let d = d - up * d.dot(up);
            if d.length() <= reach {
                self.ahead.pop_front();
                self.reached += 1;
                self.blocked_s = 0.0;
                log::info!("walk: waypoint reached at {:?}", feet.to_array());
                continue;
            }
            self.blocked_s = if blocked { self.blocked_s + dt } else { 0.0 };
            if self.blocked_s >= GIVE_UP_S {
                self.ahead.pop_front();
                self.given_up += 1;
                self.blocked_s = 0.0;
                log::info!(
                    "walk: waypoint given up (blocked for {GIVE_UP_S} s) at {:?}",
                    feet.to_array()
                );
                continue;
            }
            return Some(d.normalize());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waypoints_are_plan_coordinates_of_the_up_axis_and_blocked_ones_are_given_up() {
        let file: WalkPathFile =
            serde_json::from_str(r#"{"start": [1, 2, 10], "waypoints": [[5, 2], [5, 6]]}"#).unwrap();
        // A Y-up model: plan coordinates (e1, e2) = (x, -z), height y.
        let mut p = WalkPath::new(&file, [0.0, 0.0, 1.0], UpAxis::Y);
        assert_eq!(p.start, Vec3::new(1.0, 2.0, 9.0));
        let feet = Vec3::new(1.0, 10.0, 9.0);
        let h = p.heading(feet, false, 0.1, 0.1).unwrap();
        // Toward (5, -(2) ...) in the file: x = 5, z = -2, minus the origin's z of 1.
        let want = (Vec3::new(5.0, 10.0, -3.0) - feet).normalize();
        assert!((h - want).length() < 1e-5, "{h} {want}");
        for _ in 0..19 {
            assert!(p.heading(feet, true, 0.1, 0.1).is_some());
        }
        assert_eq!(p.given_up, 0);
        p.heading(feet, true, 0.1, 0.1);
        assert_eq!(p.given_up, 1);
        assert!(p.heading(Vec3::new(5.0, 10.0, -7.0), false, 0.1, 0.1).is_none());
        assert_eq!(p.reached, 1);
        assert!(serde_json::from_str::<WalkPathFile>(r#"{"start": [1, 2]}"#).is_err());
    }
}
