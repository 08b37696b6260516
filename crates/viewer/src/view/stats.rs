//! `--stats FILE`: one record per rendered frame of a scripted run (wall and GPU time, internal and view size,
//! whether the camera moved, when the frame was presented and which input it answers), written as JSON when the
//! run ends.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use hrtao_core::DeviceInfo;
use serde::Serialize;

use super::shot::ShotSummary;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameStat {
    /// The whole frame on the CPU clock: UI, the renderer's passes, the blit, egui, present.
    pub wall_ms: f64,
    /// The renderer's passes by GPU timestamps (0 when the device has none or they do not measure the passes:
    /// lavapipe after a raster pass).
    pub gpu_ms: f64,
    /// `gpu_ms` per section (the paper's Table 2 names).
    pub gpu_sections_ms: BTreeMap<String, f64>,
    pub internal: [u32; 2],
    pub view: [u32; 2],
    /// The camera differs from the previous rendered frame's.
    pub moving: bool,
    /// The view counts as still (the camera has rested for a moment): a full-size refinement frame.
    pub still: bool,
    /// A still frame after which the image has not converged yet (more frames follow without input).
    pub refining: bool,
    /// After this frame the image has converged at full size: the viewer rests (the log's "at rest").
    pub converged: bool,
    /// Slices (`FrameReport::slice`): the frame drew slice `slice` of `slices` (0 of 1: a whole frame).
    pub slice: u32,
    pub slices: u32,
    /// When the frame was presented (right after vkQueuePresentKHR), in milliseconds on CLOCK_MONOTONIC (the
    /// clock of Python's `time.monotonic()` on Linux).
    pub presented_ms: f64,
    /// The frame reflects input handled since the previous rendered frame: its camera changed by a drag, the
    /// wheel or a key.
    pub input: bool,
    /// With `input`: when the earliest input event not answered yet reached the viewer (CLOCK_MONOTONIC
    /// milliseconds; a drag's press counts from the frame its motion moves the camera).
    pub input_ms: Option<f64>,
    /// With `input`: when the latest input event the frame answers reached the viewer (a drag's motion, where
    /// `input_ms` may be its press). A benchmark that stamps the motion it sends matches it against this one.
    pub input_last_ms: Option<f64>,
    /// With `--ao-out`: the roughness of the frame's AO (`hrtao_core::metrics::roughness`: mean |AO − median of
    /// the 8 neighbours| over flat pixels whose own AO is below 0.95; a still image's frames over the G-buffer
    /// of the round of slices that completes them, `Latency::dump_ao`); None without `--ao-out`, when no pixel
    /// qualifies, or for the frames of a round of slices abandoned before it ended.
    pub roughness: Option<f32>,
    /// Rays traced this frame.
    pub rays: u64,
    /// The ray budget the frame was rendered with (rays per frame, `budget.rs`): what the frame-time target
    /// set; the rays traced may be fewer (a cell with all its samples takes none).
    pub rays_per_frame: u32,
    /// Values the renderer's guard found non-finite (NaN, infinite) and replaced before they entered the map or
    /// the still accumulation (`FrameReport::non_finite`): 0 on a sound device.
    pub non_finite: u32,
    /// Where `wall_ms` went on the CPU clock (consecutive spans: their sum is at most `wall_ms`).
    pub cpu_ms: CpuSplit,
    /// From the previous rendered frame's start to this one's (0 for the first): what a user sees as the frame
    /// time, including the event loop between frames.
    pub interval_ms: f64,
    /// In walk mode: the eye, in the file's coordinates.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eye: Option<[f64; 3]>,
    /// In walk mode: whether the body was blocked and the floor under it (`walk::WalkStat`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub walk: Option<super::walk::WalkStat>,
}

/// The consecutive parts of a frame's wall time, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct CpuSplit {
    /// egui's layout pass: the panel, the view's input, the overlays (`App::ui`).
    pub ui: f64,
    /// egui's tessellation and egui-ash's paint command, between the layout pass and the frame's drawing.
    pub tessellate: f64,
    /// Swapchain upkeep and acquiring the next image (and an F12 screenshot rendered this frame).
    pub acquire: f64,
    /// Recording the renderer's passes and the blit into the command buffer (and a background screenshot's tile).
    pub record: f64,
    /// egui-ash's recording: texture updates, vertex and index upload, draw calls.
    pub egui_record: f64,
    /// Submission until the frame's fence signals: the device executing the frame (on a CPU device, the
    /// rendering itself, the blit and egui's rasterisation).
    pub gpu_wait: f64,
    /// vkQueuePresentKHR.
    pub present: f64,
    /// After the present: reading back the renderer's statistics and timestamps, a background screenshot's
    /// bookkeeping.
    pub finish: f64,
}

impl CpuSplit {
    /// The per-field medians of `splits` (None when empty).
    pub fn medians<'a>(splits: impl Iterator<Item = &'a CpuSplit>) -> Option<CpuSplit> {
        let v: Vec<&CpuSplit> = splits.collect();
        let m = |f: fn(&CpuSplit) -> f64| median(v.iter().map(|s| f(s)).collect());
        Some(CpuSplit {
            ui: m(|s| s.ui)?,
            tessellate: m(|s| s.tessellate)?,
            acquire: m(|s| s.acquire)?,
            record: m(|s| s.record)?,
            egui_record: m(|s| s.egui_record)?,
            gpu_wait: m(|s| s.gpu_wait)?,
            present: m(|s| s.present)?,
            finish: m(|s| s.finish)?,
        })
    }
}

/// A stopwatch of consecutive spans: each `lap` returns the milliseconds since the previous one.
pub struct Laps(std::time::Instant);

impl Laps {
    pub fn start_at(t: std::time::Instant) -> Laps {
        Laps(t)
    }

    pub fn lap(&mut self) -> f64 {
        let now = std::time::Instant::now();
        let ms = now.duration_since(self.0).as_secs_f64() * 1e3;
        self.0 = now;
        ms
    }
}

/// The wall-clock stamps of the view's frames: when the viewer started (the pacer's clock counts from it), when
/// this frame's UI pass started and ended, and when the previous rendered frame's UI pass started.
pub struct FrameStamps {
    epoch: std::time::Instant,
    /// The frame's wall time runs from here to the present.
    pub ui_started: std::time::Instant,
    /// egui's tessellation runs from here to the frame's recording.
    pub ui_done: std::time::Instant,
    last_rendered_start: Option<std::time::Instant>,
}

impl FrameStamps {
    pub fn new() -> FrameStamps {
        let now = std::time::Instant::now();
        FrameStamps {
            epoch: now,
            ui_started: now,
            ui_done: now,
            last_rendered_start: None,
        }
    }

    /// Now, on the pacer's clock.
    pub fn now(&self) -> std::time::Duration {
        self.epoch.elapsed()
    }

    /// A frame whose UI pass started at `started` was rendered: milliseconds from the previous rendered
    /// frame's UI pass to this one's (0 for the first).
    pub fn rendered(&mut self, started: std::time::Instant) -> f64 {
        let interval = self
            .last_rendered_start
            .map_or(0.0, |t| started.saturating_duration_since(t).as_secs_f64() * 1e3);
        self.last_rendered_start = Some(started);
        interval
    }
}

#[derive(Serialize)]
struct StatsFile<'a> {
    device: &'a str,
    /// The device is a CPU rasteriser (`DeviceInfo::is_software`): tests branch on this, never on its name.
    software: bool,
    /// The frame-time target in force at the end of the run, milliseconds.
    target_ms: f64,
    scene: &'a str,
    frames: &'a [FrameStat],
    median_moving_wall_ms: Option<f64>,
    median_still_wall_ms: Option<f64>,
    /// The index in `frames` of the first frame after which the image had converged (None: it never did).
    converged_frame: Option<usize>,
    /// Per-field medians of the moving frames' `cpu_ms`.
    median_moving_cpu_ms: Option<CpuSplit>,
    /// Non-finite values the guard replaced over the run (the frames' `non_finite`): 0 on a sound device.
    non_finite: u64,
    /// A background screenshot (--screenshot-size) written during the run.
    screenshot: Option<&'a ShotSummary>,
    /// Frames the viewer kept in flight (1 or 2), and how many completed after the next frame began.
    frames_in_flight: usize,
    overlapped_frames: u64,
}

pub struct StatsLog {
    path: PathBuf,
    pub frames: Vec<FrameStat>,
    pub screenshot: Option<ShotSummary>,
}

impl StatsLog {
    pub fn new(path: PathBuf) -> StatsLog {
        StatsLog {
            path,
            frames: Vec::new(),
            screenshot: None,
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Median wall time of the moving (or still) frames.
    pub fn median_wall_ms(&self, moving: bool) -> Option<f64> {
        median(
            self.frames
                .iter()
                .filter(|f| f.moving == moving)
                .map(|f| f.wall_ms)
                .collect(),
        )
    }

    /// Writes the file; `in_flight`: the frames in flight kept, and those completed after the next frame
    /// began.
    pub fn write(
        &self,
        device: &DeviceInfo,
        target_ms: f64,
        scene: &str,
        in_flight: (usize, u64),
    ) -> Result<()> {
        let file = StatsFile {
            device: &device.name,
            software: device.is_software,
            target_ms,
            scene,
            frames: &self.frames,
            median_moving_wall_ms: self.median_wall_ms(true),
            median_still_wall_ms: self.median_wall_ms(false),
            converged_frame: self.frames.iter().position(|f| f.converged),
            median_moving_cpu_ms: CpuSplit::medians(
                self.frames.iter().filter(|f| f.moving).map(|f| &f.cpu_ms),
            ),
            non_finite: self.frames.iter().map(|f| f.non_finite as u64).sum(),
            screenshot: self.screenshot.as_ref(),
            frames_in_flight: in_flight.0,
            overlapped_frames: in_flight.1,
        };
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        let text = serde_json::to_string_pretty(&file)?;
        std::fs::write(&self.path, text).with_context(|| format!("cannot write {}", self.path.display()))
    }
}

/// The panel's statistics about the scene's instancing: its unique meshes, which of them several instances share
/// (an assembly's bolts and nuts), and its instances (how many the file or the user hid).
pub fn scene_rows(scene: &hrtao_scene::Scene) -> Vec<(&'static str, String)> {
    let shared = hrtao_scene::cad::shared_meshes(scene);
    let mut rows = vec![(
        "meshes",
        format!("{} unique, {} shared", scene.meshes.len(), shared.len()),
    )];
    if !shared.is_empty() {
        // Short names, so that the row never widens the panel (a CAD file's part names can be long).
        let short: Vec<(String, usize)> = shared
            .into_iter()
            .map(|(name, n)| (short_name(&name), n))
            .collect();
        rows.push(("", hrtao_scene::cad::shared_meshes_text(&short, 3)));
    }
    let hidden = scene.instances.iter().filter(|i| !i.visible).count();
    rows.push((
        "instances",
        if hidden > 0 {
            format!("{}, {hidden} hidden", scene.instances.len())
        } else {
            scene.instances.len().to_string()
        },
    ));
    rows
}

/// At most `SHORT_NAME` characters of a mesh name, "…" marking a cut.
const SHORT_NAME: usize = 12;
fn short_name(name: &str) -> String {
    if name.chars().count() <= SHORT_NAME {
        name.to_string()
    } else {
        format!("{}…", name.chars().take(SHORT_NAME - 1).collect::<String>())
    }
}

/// The median of the finite values (`hrtao_core::stats::median`), None when there are none.
pub fn median(v: Vec<f64>) -> Option<f64> {
    Some(hrtao_core::stats::median(&v)).filter(|m| !m.is_nan())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_moving_and_still_frames() {
        let mut log = StatsLog::new("x.json".into());
        for (ms, moving) in [
            (10.0, true),
            (30.0, true),
            (20.0, true),
            (5.0, false),
            (7.0, false),
        ] {
            log.frames.push(FrameStat {
                wall_ms: ms,
                gpu_ms: 0.0,
                gpu_sections_ms: BTreeMap::new(),
                internal: [1, 1],
                view: [1, 1],
                moving,
                still: !moving,
                refining: !moving,
                converged: false,
                slice: 0,
                slices: 1,
                presented_ms: 0.0,
                input: false,
                input_ms: None,
                input_last_ms: None,
                roughness: None,
                rays: 0,
                rays_per_frame: 0,
                non_finite: 0,
                cpu_ms: CpuSplit::default(),
                interval_ms: 0.0,
                eye: None,
                walk: None,
            });
        }
        assert_eq!(log.median_wall_ms(true), Some(20.0));
        assert_eq!(log.median_wall_ms(false), Some(6.0));
        assert_eq!(median(Vec::new()), None);
    }

    #[test]
    fn scene_rows_count_unique_meshes_shared_meshes_and_instances() {
        use hrtao_scene::{Instance, Mesh, Scene};
        let mut scene = Scene::new("bolted");
        for name in ["plate", "bolt", "nut"] {
            scene.meshes.push(Mesh {
                name: name.into(),
                primitives: Vec::new(),
            });
        }
        // One plate, four bolts, six nuts (one hidden).
        for (mesh, n) in [(0u32, 1), (1, 4), (2, 6)] {
            for k in 0..n {
                scene.instances.push(Instance {
                    mesh,
                    transform: glam::Mat4::IDENTITY,
                    name: format!("{mesh}.{k}"),
                    visible: !(mesh == 2 && k == 0),
                });
            }
        }
        assert_eq!(
            scene_rows(&scene),
            [
                ("meshes", "3 unique, 2 shared".to_string()),
                ("", "nut ×6, bolt ×4".to_string()),
                ("instances", "11, 1 hidden".to_string()),
            ]
        );
        assert_eq!(
            short_name("a_very_long_part_name_from_a_cad_file"),
            "a_very_long…"
        );
        let four: Vec<(String, usize)> = (0..4).map(|i| (format!("m{i}"), 5 - i)).collect();
        assert_eq!(
            hrtao_scene::cad::shared_meshes_text(&four, 3),
            "m0 ×5, m1 ×4, m2 ×3, and 1 more"
        );
        scene.instances.truncate(1);
        assert_eq!(
            scene_rows(&scene),
            [
                ("meshes", "3 unique, 0 shared".to_string()),
                ("instances", "1".to_string()),
            ]
        );
    }

    #[test]
    fn laps_are_consecutive_and_the_split_adds_up() {
        let t0 = std::time::Instant::now();
        let mut laps = Laps::start_at(t0);
        std::thread::sleep(std::time::Duration::from_millis(2));
        let a = laps.lap();
        let b = laps.lap();
        let whole = t0.elapsed().as_secs_f64() * 1e3;
        assert!(a >= 2.0 && b >= 0.0 && a + b <= whole, "{a} {b} {whole}");
        let a = CpuSplit {
            ui: 1.0,
            gpu_wait: 3.0,
            ..CpuSplit::default()
        };
        let b = CpuSplit {
            ui: 3.0,
            gpu_wait: 1.0,
            finish: 0.5,
            ..CpuSplit::default()
        };
        let m = CpuSplit::medians([a, b].iter()).unwrap();
        assert_eq!((m.ui, m.gpu_wait, m.finish, m.present), (2.0, 2.0, 0.25, 0.0));
        assert_eq!(CpuSplit::medians(std::iter::empty()), None);
        let json = serde_json::to_value(m).unwrap();
        for k in [
            "ui",
            "tessellate",
            "acquire",
            "record",
            "egui_record",
            "gpu_wait",
            "present",
            "finish",
        ] {
            assert!(json[k].is_number(), "{k} in {json}");
        }
    }
}
