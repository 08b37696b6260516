//! Viewer preferences persisted between runs as a small JSON file: AO settings, render scale, the automatic ray
//! budget, screenshot options and camera bookmarks. A missing file gives defaults; a corrupt one gives defaults
//! plus a message for the UI (the file is only overwritten when the user changes something).
use std::path::{Path, PathBuf};

use hrtao_core::{AoSettings, Camera};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bookmark {
    pub name: String,
    /// The scene the bookmark was taken in (shown; bookmarks work in any scene).
    pub scene: String,
    pub camera: Camera,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Prefs {
    /// AO settings (the radius is reset to the scene's default when a scene is opened): the viewer's only copy.
    /// Read leniently: a setting another version wrote that this one does not know, or with another type, is
    /// skipped (logged) instead of discarding the whole file.
    #[serde(deserialize_with = "lenient_settings")]
    pub settings: AoSettings,
    /// Largest internal resolution as a fraction of the 3D view (None: 1): still images are rendered at it.
    pub max_render_scale: Option<f32>,
    /// Ray budget in rays per frame (converted to rays per pixel at the current internal resolution). With the
    /// frame-time target on, each scene opened starts from the default and the target moves it from there.
    pub rays_per_frame: u32,
    /// Adapt the ray budget and the moving render scale to meet the frame-time target.
    pub auto_budget: bool,
    /// The user's frame-time target; None: the device's (a frame per display refresh on a GPU, 100 ms on a
    /// software device: `pacer::DeviceModel::target_ms`).
    pub frame_target_ms: Option<f32>,
    /// Frames submitted before the host waits for the oldest, 1 or 2; None: the device's (2 on a GPU, where
    /// the host records a frame while the device runs the last; 1 on a software device, whose frames use the
    /// host's cores: `frames_in_flight`). `HRTAO_FRAMES_IN_FLIGHT` overrides it (the window tests set 2).
    pub frames_in_flight: Option<u32>,
    /// How rays are traced (ray queries or ray-tracing pipelines); None: the device's choice (ray queries where
    /// it has them). Read when the device is opened: a change applies at the next start. `--ray-backend` and
    /// `HRTAO_RAY_BACKEND` override it.
    pub ray_backend: Option<hrtao_core::RayBackend>,
    /// Files of older versions hold `target_ms`, always written, 100 unless the user changed it: read once by
    /// `load` (100 was the default, not a choice: the device's target; another value is the user's), never
    /// written.
    #[serde(rename = "target_ms", skip_serializing)]
    pub legacy_target_ms: Option<f32>,
    /// Where F12 saves (None: the pictures directory, see `pictures_dir`). Files of older versions name a
    /// `screenshot_dir` relative to the working directory: ignored.
    pub screenshot_folder: Option<PathBuf>,
    pub screenshot_custom: bool,
    pub screenshot_width: u32,
    pub screenshot_height: u32,
    /// Frames rendered for a window-size screenshot, at most 4 (a custom size renders until converged).
    pub screenshot_frames: u32,
    pub bookmarks: Vec<Bookmark>,
    pub dark_theme: bool,
    /// How STEP/IGES files are tessellated when opened (the panel's load options).
    pub cad_load: super::load_options::CadLoadOptions,
    /// How meshes without normals of their own are smoothed when opened (the panel's load options).
    pub mesh_load: super::load_options::MeshLoadOptions,
    /// Recently opened files, most recent first (canonical paths, at most `recent::CAP`; see `recent.rs`).
    pub recent: Vec<PathBuf>,
    /// The up axis the user chose per file, newest first (`up_axis.rs`).
    pub up_axes: Vec<super::up_axis::FileUp>,
    /// Reload the open file when it changes on disk (`watch.rs`).
    pub auto_reload: bool,
    /// Walk mode's measures (`walk.rs`).
    pub walk: super::walk::WalkSettings,
}

impl Default for Prefs {
    fn default() -> Self {
        Prefs {
            settings: AoSettings::default(),
            max_render_scale: None,
            rays_per_frame: super::pacer::DEFAULT_RAYS_PER_FRAME,
            auto_budget: true,
            frame_target_ms: None,
            frames_in_flight: None,
            ray_backend: None,
            legacy_target_ms: None,
            screenshot_folder: None,
            screenshot_custom: false,
            screenshot_width: 3840,
            screenshot_height: 2160,
            screenshot_frames: 16,
            bookmarks: Vec::new(),
            dark_theme: true,
            cad_load: Default::default(),
            mesh_load: Default::default(),
            recent: Vec::new(),
            up_axes: Vec::new(),
            auto_reload: true,
            walk: Default::default(),
        }
    }
}

/// The frame-time target every older version wrote by default.
const LEGACY_DEFAULT_TARGET_MS: f32 = 100.0;

/// The ray backend the device is opened with: the command line's or environment's (`--ray-backend`,
/// `HRTAO_RAY_BACKEND`), else the saved one, else None (the device chooses).
pub fn ray_backend(
    command_line: Option<hrtao_core::RayBackend>,
    saved: Option<hrtao_core::RayBackend>,
) -> Option<hrtao_core::RayBackend> {
    command_line.or(saved)
}

/// The frames in flight the viewer keeps: `HRTAO_FRAMES_IN_FLIGHT` (`env`) if it names 1 or 2, else the
/// user's choice, else 2 on a GPU and 1 on a software device (whose frames run on the host's cores: recording
/// the next frame meanwhile only takes cores from this one).
pub fn frames_in_flight(env: Option<&str>, chosen: Option<u32>, software: bool) -> usize {
    let max = super::present::MAX_FRAMES_IN_FLIGHT as u32;
    let valid = |n: u32| (1..=max).contains(&n).then_some(n as usize);
    env.and_then(|v| v.trim().parse().ok())
        .and_then(valid)
        .or_else(|| chosen.and_then(valid))
        .unwrap_or(if software { 1 } else { 2 })
}

/// The user's pictures directory: `$XDG_PICTURES_DIR`, else the XDG user directory (`user-dirs.dirs`), else
/// `~/Pictures`; relative paths and a missing home give None.
pub fn pictures_dir() -> Option<PathBuf> {
    let from_env = std::env::var_os("XDG_PICTURES_DIR").map(PathBuf::from);
    let home_pictures = dirs::home_dir().map(|h| h.join("Pictures"));
    [from_env, dirs::picture_dir(), home_pictures]
        .into_iter()
        .flatten()
        .find(|p| p.is_absolute())
}

/// `$XDG_CONFIG_HOME/hrtao/viewer.json`, else `~/.config/hrtao/viewer.json` (`dirs::config_dir`: an empty or
/// relative `XDG_CONFIG_HOME` is ignored, as the XDG specification says), else `./hrtao-viewer.json`.
pub fn default_path() -> PathBuf {
    match dirs::config_dir() {
        Some(dir) => dir.join("hrtao/viewer.json"),
        None => PathBuf::from("hrtao-viewer.json"),
    }
}

/// Loads the preferences; on a corrupt file returns defaults and the error message.
pub fn load(path: &Path) -> (Prefs, Option<String>) {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return (Prefs::default(), None),
        Err(e) => {
            return (
                Prefs::default(),
                Some(format!("cannot read {}: {e}", path.display())),
            )
        }
    };
    match serde_json::from_str::<Prefs>(&text) {
        Ok(mut p) => {
            if let Err(e) = p.settings.validate() {
                p.settings = AoSettings::default();
                return (
                    p,
                    Some(format!(
                        "{}: invalid AO settings ({e}); using defaults",
                        path.display()
                    )),
                );
            }
            p.bookmarks.retain(|b| b.camera.validate().is_ok());
            super::recent::sanitize(&mut p.recent, super::recent::CAP);
            // The older versions' default of 100 ms was written whether chosen or not: the device's target.
            if let Some(t) = p.legacy_target_ms.take() {
                if p.frame_target_ms.is_none() && t != LEGACY_DEFAULT_TARGET_MS {
                    p.frame_target_ms = Some(t);
                }
            }
            p.frame_target_ms = p.frame_target_ms.filter(|t| t.is_finite() && *t > 0.0);
            (p, None)
        }
        Err(e) => (
            Prefs::default(),
            Some(format!("{} is corrupt ({e}); using defaults", path.display())),
        ),
    }
}

fn lenient_settings<'de, D: serde::Deserializer<'de>>(d: D) -> Result<AoSettings, D::Error> {
    let value = serde_json::Value::deserialize(d)?;
    let (settings, skipped) = AoSettings::from_json_lenient(&value);
    if !skipped.is_empty() {
        log::warn!("preferences: AO settings {skipped:?} skipped (unknown or invalid in this version)");
    }
    Ok(settings)
}

pub fn save(path: &Path, prefs: &Prefs) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, serde_json::to_string_pretty(prefs)?)?;
    std::fs::rename(&tmp, path)?;
    Ok(())
}

/// Where the preferences are kept and what was last written there: changes are saved at most once a second
/// (and when the window closes). None with `--no-config`.
pub struct PrefsFile {
    path: Option<PathBuf>,
    saved: Prefs,
    saved_at: std::time::Instant,
}

impl PrefsFile {
    /// Reads `path` (None: nothing is read or saved): the preferences and a message for the user when the file
    /// could not be used.
    pub fn open(path: Option<PathBuf>) -> (PrefsFile, Prefs, Option<String>) {
        let (prefs, msg) = match &path {
            Some(p) => load(p),
            None => (Prefs::default(), None),
        };
        let file = PrefsFile {
            path,
            saved: prefs.clone(),
            saved_at: std::time::Instant::now(),
        };
        (file, prefs, msg)
    }

    /// Saves `prefs` if they changed, unless the last save was under a second ago (`force`: now). An error names
    /// the file (and is not retried until the preferences change again).
    pub fn maybe_save(&mut self, prefs: &Prefs, force: bool) -> Result<(), String> {
        let Some(path) = &self.path else {
            return Ok(());
        };
        if *prefs == self.saved || (!force && self.saved_at.elapsed() < std::time::Duration::from_secs(1)) {
            return Ok(());
        }
        self.saved_at = std::time::Instant::now();
        self.saved = prefs.clone();
        save(path, prefs).map_err(|e| format!("cannot save settings to {}: {e:#}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_ray_backend_wins_over_the_saved_one() {
        use hrtao_core::RayBackend::{Pipeline, Query};
        assert_eq!(ray_backend(None, None), None);
        assert_eq!(ray_backend(None, Some(Pipeline)), Some(Pipeline));
        assert_eq!(ray_backend(Some(Query), Some(Pipeline)), Some(Query));
        // Saved as the panel writes it, read back.
        let p = Prefs {
            ray_backend: Some(Pipeline),
            ..Prefs::default()
        };
        let json = serde_json::to_string(&p).unwrap();
        assert!(json.contains("\"ray_backend\":\"pipeline\""), "{json}");
        assert_eq!(
            serde_json::from_str::<Prefs>(&json).unwrap().ray_backend,
            Some(Pipeline)
        );
    }

    #[test]
    fn frames_in_flight_by_device_choice_and_environment() {
        assert_eq!(frames_in_flight(None, None, false), 2);
        assert_eq!(frames_in_flight(None, None, true), 1);
        assert_eq!(frames_in_flight(None, Some(2), true), 2);
        assert_eq!(frames_in_flight(None, Some(1), false), 1);
        assert_eq!(frames_in_flight(Some("2"), Some(1), true), 2);
        // Out of range or garbage: ignored.
        assert_eq!(frames_in_flight(Some("3"), Some(7), true), 1);
        assert_eq!(frames_in_flight(Some("x"), None, false), 2);
    }

    #[test]
    fn round_trip_missing_and_corrupt() {
        let dir = std::env::temp_dir().join(format!("hrtao-prefs-{}", std::process::id()));
        let path = dir.join("viewer.json");
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(load(&path), (Prefs::default(), None));
        let mut p = Prefs::default();
        p.settings.map.rays_per_pixel = 9;
        p.bookmarks.push(Bookmark {
            name: "a".into(),
            scene: "s".into(),
            camera: Camera::default(),
        });
        save(&path, &p).unwrap();
        assert_eq!(load(&path), (p, None));
        // A file of another version: an unknown setting and a changed type keep the rest.
        std::fs::write(
            &path,
            r#"{"settings": {"ao_radius": 3.5, "near_weight": 1.0, "shaded": 2.0}, "max_render_scale": 0.5}"#,
        )
        .unwrap();
        let (old, msg) = load(&path);
        assert_eq!(
            (old.settings.map.ao_radius, old.max_render_scale, msg),
            (3.5, Some(0.5), None)
        );
        assert!(old.settings.display.shaded);
        std::fs::write(&path, "{ not json").unwrap();
        let (d, msg) = load(&path);
        assert_eq!(d, Prefs::default());
        assert!(msg.unwrap().contains("corrupt"));
        // An older file's target: its default 100 ms becomes the device's, another value stays the user's;
        // a new file's choice is kept and the old key is not written again.
        std::fs::write(&path, r#"{"target_ms": 100.0}"#).unwrap();
        assert_eq!(load(&path).0.frame_target_ms, None);
        std::fs::write(&path, r#"{"target_ms": 33.0}"#).unwrap();
        let (chosen, _) = load(&path);
        assert_eq!(
            (chosen.frame_target_ms, chosen.legacy_target_ms),
            (Some(33.0), None)
        );
        save(&path, &chosen).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(!text.contains("\"target_ms\""), "{text}");
        assert_eq!(load(&path), (chosen, None));
        std::fs::write(&path, r#"{"frame_target_ms": -5.0}"#).unwrap();
        assert_eq!(load(&path).0.frame_target_ms, None);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
