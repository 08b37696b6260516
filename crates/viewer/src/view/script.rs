//! Scripted runs: `--frames`, `--orbit`, `--walk-path` (walked by walk/path.rs once the scene is open),
//! `--set-at-frame`, `--open-at-frame`, `--resize-at-frame`, the screenshots at the end, `--exit` and
//! `--timeout`. Like a panel, the script reads what it needs of the viewer and returns commands, which the viewer
//! applies (`Viewer::apply`): the steps are counted in rendered frames (one `step` per rendered frame
//! completed), the orbit turns the camera in the UI pass.
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};

use super::command::Command;
use super::nav::{self, Nav};
use super::shots::ShotRequest;
use crate::cli::ViewArgs;

/// The scripted run's hooks, parsed from the arguments before the window opens (a bad one is the command's
/// error).
#[derive(Clone)]
pub(super) struct ScriptHooks {
    /// --resize-at-frame K WxH.
    resize: Option<(u32, (u32, u32))>,
    /// --set-at-frame K JSON (repeatable).
    set_at_frame: Vec<(u32, String)>,
}

impl ScriptHooks {
    pub fn parse(args: &ViewArgs) -> Result<ScriptHooks> {
        let resize = match crate::cli::frame_pairs("--resize-at-frame", &args.resize_at_frame)?.as_slice() {
            [] => None,
            [(k, wh)] => Some((
                *k,
                crate::cli::parse_size(wh).map_err(|e| anyhow!("--resize-at-frame: {e}"))?,
            )),
            _ => bail!("--resize-at-frame is given once"),
        };
        let set_at_frame = crate::cli::set_at_frame(&args.set_at_frame)?;
        Ok(ScriptHooks { resize, set_at_frame })
    }
}

/// Seconds a scripted run may take: --timeout, or 600 plus 600 per million pixels of a background screenshot.
fn scripted_timeout(args: &ViewArgs) -> u64 {
    let shot_pixels = args.screenshot_size.map_or(0, |(w, h)| w as u64 * h as u64);
    args.timeout
        .unwrap_or(600 + 600 * shot_pixels.div_ceil(1_000_000))
}

/// What a step of the script reads of the viewer.
pub(super) struct ScriptView {
    /// The last frame shows a converged image at the full internal size.
    pub converged: bool,
    pub loading: bool,
    /// A scripted walk is under way.
    pub walking: bool,
}

/// Scripted-mode state.
pub(super) struct Script {
    frames: Option<u32>,
    /// --orbit N: frames still to orbit, and whether the run waits for convergence after them.
    orbit_left: u32,
    wait_converged: bool,
    screenshot: Option<PathBuf>,
    screenshot_ui: Option<PathBuf>,
    screenshot_frames: u32,
    /// --screenshot-size: --screenshot is rendered in the background at this size (started once).
    screenshot_size: Option<(u32, u32)>,
    shot_started: bool,
    resize: Option<(u32, (u32, u32))>,
    open: Option<(u32, String)>,
    /// --set-at-frame: settings (JSON) applied after K rendered frames, as the panel applies them.
    set_at_frame: Vec<(u32, String)>,
    /// --exit: the run ends after its frames, and an error ends it.
    pub exit: bool,
    deadline: Option<Instant>,
    /// Rendered frames counted so far.
    pub rendered: u32,
    /// The run is over (its screenshots taken, its statistics written).
    pub done: bool,
    /// The --screenshot-ui capture was asked for (once).
    ui_captured: bool,
}

impl Script {
    pub fn new(args: &ViewArgs, hooks: ScriptHooks) -> Script {
        Script {
            frames: args
                .frames
                .or(args.orbit.map(|_| 0))
                .or(args.walk_path.as_ref().map(|_| 0)),
            orbit_left: args.orbit.unwrap_or(0),
            wait_converged: args.orbit.is_some(),
            screenshot: args.screenshot.clone(),
            screenshot_ui: args.screenshot_ui.clone(),
            screenshot_frames: args.screenshot_frames,
            screenshot_size: args.screenshot_size,
            shot_started: false,
            resize: hooks.resize,
            set_at_frame: hooks.set_at_frame,
            open: match args.open_at_frame.as_slice() {
                [k, file] => k.parse::<u32>().ok().map(|k| (k, file.clone())),
                _ => None,
            },
            exit: args.exit,
            deadline: Some(scripted_timeout(args))
                .filter(|&t| (args.exit || args.exit_after.is_some()) && t > 0)
                .map(|t| Instant::now() + Duration::from_secs(t)),
            rendered: 0,
            done: false,
            ui_captured: false,
        }
    }

    /// A scripted run is counting frames (the view renders every frame).
    pub fn running(&self) -> bool {
        self.frames.is_some() && !self.done
    }

    /// A failed screenshot ends the run: a scripted run's background screenshot.
    pub fn shot_is_fatal(&self) -> bool {
        self.screenshot_size.is_some() && self.frames.is_some()
    }

    /// `--timeout` has passed (said once).
    pub fn timed_out(&mut self) -> bool {
        match self.deadline {
            Some(d) if Instant::now() > d => {
                self.deadline = None;
                true
            }
            _ => false,
        }
    }

    /// One step of `--orbit` (2° about the pivot, around the world up axis), once a scene shows an image.
    pub fn orbit(&mut self, nav: &Nav, ready: bool) -> Option<Command> {
        if self.frames.is_none() || self.orbit_left == 0 || !ready {
            return None;
        }
        self.orbit_left -= 1;
        let cam = nav::orbit(&nav.cam, nav.pivot, nav.world_up.vector(), 2f32.to_radians(), 0.0);
        Some(Command::Camera {
            cam,
            pivot: nav.pivot,
        })
    }

    /// A rendered frame completed: counts it, resizes, opens, applies settings, and once the frames are done
    /// (the orbit converged, the walk and a scripted open finished) captures the window, then ends the run
    /// (`Command::FinishScript`: the screenshots, the statistics, the exit).
    pub fn step(&mut self, v: &ScriptView) -> Vec<Command> {
        let mut out = Vec::new();
        let Some(frames) = self.frames else {
            return out;
        };
        if self.done {
            return out;
        }
        self.rendered += 1;
        let n = self.rendered;
        if let Some((k, (w, h))) = self.resize {
            if n == k {
                log::info!("scripted resize to {w}x{h}");
                out.push(Command::WindowSize(w, h));
            }
        }
        // A load starts at once: the run waits for it below.
        let mut loading = v.loading;
        if let Some((k, file)) = self.open.clone() {
            if n == k {
                log::info!("scripted open of {file}");
                out.push(Command::Open(file));
                loading = true;
            }
        }
        for (_, json) in self.set_at_frame.iter().filter(|(k, _)| *k == n) {
            log::info!("scripted settings after frame {n}: {json}");
            out.push(Command::SetJson {
                json: json.clone(),
                what: format!("--set-at-frame {n}"),
            });
        }
        if self.orbit_left > 0 || v.walking || (self.wait_converged && !v.converged) {
            return out;
        }
        if n >= frames && loading {
            // Let a scripted open finish (success or error) before the screenshots.
            return out;
        }
        if n >= frames && !self.ui_captured {
            if let Some(path) = self.screenshot_ui.clone() {
                // Captured with the next presented frame (after --frames N, or once --orbit has converged).
                self.ui_captured = true;
                out.push(Command::CaptureWindow(path));
                return out;
            }
        }
        if n >= frames {
            let mut after_shot = false;
            if let (Some(size), Some(path)) = (self.screenshot_size, self.screenshot.clone()) {
                // Rendered in the background while the window keeps drawing: the run ends once it is written.
                if !self.shot_started {
                    self.shot_started = true;
                    out.push(Command::BackgroundShot { size, path });
                }
                after_shot = true;
            }
            out.push(Command::FinishScript { after_shot });
        }
        out
    }

    /// The end's screenshot at the window's size (`--screenshot` without `--screenshot-size`).
    pub fn screenshot(&self) -> Option<ShotRequest> {
        let path = self
            .screenshot
            .clone()
            .filter(|_| self.screenshot_size.is_none())?;
        Some(ShotRequest {
            size: None,
            frames: self.screenshot_frames,
            path,
        })
    }
}
