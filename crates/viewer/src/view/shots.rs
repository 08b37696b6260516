//! The viewer's screenshots in flight: one at the window's size asked for by F12 or the button (taken before
//! the next frame), or one custom-size `shot::BackgroundShot` rendering tile by tile inside the viewer's frames,
//! then its PNG written on a thread. One at a time. Also where a screenshot goes (`path`: the panel's folder,
//! the model's name and the time).
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver};

use anyhow::{Context, Result};
use ash::vk;
use hrtao_core::SceneGpu;

use super::shot::{BackgroundShot, Finished, ShotSummary};

/// A screenshot at the 3D view's size (None) or another, of `frames` frames, taken before the next frame.
pub struct ShotRequest {
    pub size: Option<(u32, u32)>,
    pub frames: u32,
    pub path: PathBuf,
}

/// A background screenshot's PNG being written on its own thread.
struct Saving {
    summary: ShotSummary,
    rx: Receiver<Result<(), String>>,
}

#[derive(Default)]
pub struct Shots {
    /// F12/the button at the window's size.
    pub pending: Option<ShotRequest>,
    background: Option<BackgroundShot>,
    saving: Option<Saving>,
}

impl Shots {
    /// A background screenshot is rendering.
    pub fn rendering(&self) -> bool {
        self.background.is_some()
    }

    /// Rendering or writing its PNG.
    pub fn in_background(&self) -> bool {
        self.background.is_some() || self.saving.is_some()
    }

    /// Anything pending, rendering or being written.
    pub fn busy(&self) -> bool {
        self.pending.is_some() || self.in_background()
    }

    /// The progress for the panels: fraction, text, whether it can still be cancelled.
    pub fn progress(&self) -> Option<(f32, String, bool)> {
        if let Some(s) = &self.background {
            return Some((s.progress(), s.status(), true));
        }
        self.saving.as_ref().map(|s| {
            let [w, h] = s.summary.size;
            (1.0, format!("{w}×{h}: writing the PNG"), false)
        })
    }

    /// Starts a background screenshot made by `make` (called only when none is in progress); the message for the
    /// user, or the error.
    pub fn start(
        &mut self,
        (w, h): (u32, u32),
        make: impl FnOnce() -> Result<BackgroundShot>,
    ) -> Result<String, String> {
        if self.in_background() {
            return Err("a screenshot is already in progress".into());
        }
        let s = make().map_err(|e| format!("screenshot failed: {e:#}"))?;
        let msg = format!(
            "rendering a {w}×{h} screenshot in the background ({} tiles)",
            s.tiles()
        );
        self.background = Some(s);
        Ok(msg)
    }

    /// Drops the background screenshot; whether there was one.
    pub fn cancel(&mut self) -> bool {
        self.background.take().is_some()
    }

    /// Records one frame of the background screenshot's current tile into the viewer's command buffer.
    pub fn record(&mut self, cmd: vk::CommandBuffer, scene: &SceneGpu, scene_f: u32) -> Result<()> {
        match &mut self.background {
            Some(s) => s.record(cmd, scene, scene_f),
            None => Ok(()),
        }
    }

    /// After the viewer's frame completed: the background screenshot's frame; a finished image is written on a
    /// thread. The shot's GPU milliseconds, or its error (the shot is dropped).
    pub fn finish_frame(&mut self, viewer_rendered: bool) -> Result<f64, String> {
        let Some(s) = &mut self.background else {
            return Ok(0.0);
        };
        s.viewer_frames += 1;
        s.viewer_rendered += viewer_rendered as u32;
        match s.finish() {
            Ok(None) => Ok(s.last_gpu_ms),
            Ok(Some(done)) => {
                let ms = s.last_gpu_ms;
                self.background = None;
                self.save(done);
                Ok(ms)
            }
            Err(e) => {
                self.background = None;
                Err(format!("screenshot failed: {e:#}"))
            }
        }
    }

    fn save(&mut self, done: Finished) {
        let (tx, rx) = mpsc::channel();
        let summary = done.summary;
        let (path, [w, h]) = (summary.path.clone(), summary.size);
        let rgba = done.rgba;
        std::thread::spawn(move || {
            let result = hrtao_core::imageio::write_png(&path, w, h, &rgba)
                .with_context(|| format!("cannot write {}", path.display()));
            let _ = tx.send(result.map_err(|e| format!("{e:#}")));
        });
        self.saving = Some(Saving { summary, rx });
    }

    /// The PNG writer's result once it has finished: the summary, or the error.
    pub fn poll_saving(&mut self) -> Option<Result<ShotSummary, String>> {
        let saving = self.saving.as_ref()?;
        let result = match saving.rx.try_recv() {
            Ok(r) => r,
            Err(mpsc::TryRecvError::Empty) => return None,
            Err(mpsc::TryRecvError::Disconnected) => Err("the PNG writer stopped".into()),
        };
        let saving = self.saving.take()?;
        Some(
            result
                .map(|()| saving.summary)
                .map_err(|e| format!("screenshot failed: {e}")),
        )
    }
}

/// Creates the folder `path` goes into.
pub fn create_folder(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    Ok(())
}

/// Writes a screenshot's RGBA pixels as a PNG (its folder created first).
pub fn write_png(path: &Path, (w, h): (u32, u32), rgba: &[u8]) -> Result<()> {
    create_folder(path)?;
    hrtao_core::imageio::write_png(path, w, h, rgba)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// `MODEL-YYYYMMDD-HHMMSS.png` in `folder` (the panel's), else the pictures directory, else the working
/// directory.
pub fn path(folder: Option<PathBuf>, model: &str) -> PathBuf {
    let folder = folder.or_else(super::prefs::pictures_dir).unwrap_or_default();
    unique_path(&folder, &screenshot_name(model, jiff::Zoned::now()))
}

/// `MODEL-YYYYMMDD-HHMMSS` in local time, the model's name made safe for a file name.
fn screenshot_name(model: &str, t: jiff::Zoned) -> String {
    let model: String = model
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    let model = model.trim_start_matches('.');
    let model = if model.is_empty() { "hrtao" } else { model };
    format!("{model}-{}", t.strftime("%Y%m%d-%H%M%S"))
}

/// `folder/NAME.png`, or `folder/NAME-2.png`, `-3`… when that file exists (two shots in one second).
fn unique_path(folder: &Path, name: &str) -> PathBuf {
    (1..)
        .map(|i| match i {
            1 => folder.join(format!("{name}.png")),
            _ => folder.join(format!("{name}-{i}.png")),
        })
        .find(|p| !p.exists())
        .expect("a free name")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_and_sizes() {
        let t = jiff::Timestamp::from_second(1_704_067_200)
            .unwrap()
            .to_zoned(jiff::tz::TimeZone::UTC);
        assert_eq!(screenshot_name("gearbox", t.clone()), "gearbox-20240101-000000");
        assert_eq!(screenshot_name("../a b", t.clone()), "_a_b-20240101-000000");
        assert_eq!(screenshot_name("", t), "hrtao-20240101-000000");
        let dir = std::env::temp_dir().join(format!("hrtao-unique-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let first = unique_path(&dir, "m");
        assert_eq!(first, dir.join("m.png"));
        std::fs::write(&first, b"").unwrap();
        assert_eq!(unique_path(&dir, "m"), dir.join("m-2.png"));
        std::fs::remove_dir_all(&dir).unwrap();
        use crate::cli::parse_size;
        assert_eq!(parse_size("480x270").unwrap(), (480, 270));
        assert!(parse_size("0x10").is_err() && parse_size("abc").is_err());
    }
}
