//! `hrtao thumbnail --size N INPUT OUTPUT.png`: a file manager's preview of a model (packaging/hrtao.thumbnailer,
//! the freedesktop thumbnailer spec). The render is `hrtao render`'s ([`render_cmd::ready`]): the setup rules
//! (`NAME.camera.json` beside the model, else a fitted view from the format's up axis), the HRTAO mode with its
//! default settings, a few frames at N × N; then the image is cut to the model (the background transparent,
//! cropped to the model's rectangle with a small margin), so its longest side is at most N.
//!
//! A file too big or too slow gets no thumbnail rather than a stuck file manager:
//! - **file size**: a model file over `--max-file-mb` is refused before it is read;
//! - **memory**: the scene's load is bounded by `--max-memory-mb` (`HRTAO_MAX_SCENE_MB`, which the loaders and
//!   the STEP/IFC workers' address-space limits follow) and the device's allocations by twice that plus 512 MiB
//!   (`HRTAO_DEVICE_MEMORY_LIMIT`). No address-space limit is set on this process itself: GPU drivers reserve
//!   far more address space than they use;
//! - **time**: a watchdog ends the process after `--timeout` seconds (exit status 1; the workers die with it),
//!   and no frame starts after half of it once one is done.
//!
//! The PNG is written to a temporary file beside OUTPUT and renamed onto it at the end, under the lock the
//! watchdog takes: OUTPUT is either the whole thumbnail or untouched.
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, FromArgMatches};
use hrtao_core::gpu::{GPixel, NO_INSTANCE};
use hrtao_core::FrameDesc;

use crate::cli::{RenderArgs, ThumbnailArgs};
use crate::render_cmd::{self, Ready};
use crate::setup::Installed;

pub fn run(args: &ThumbnailArgs) -> Result<()> {
    let t0 = Instant::now();
    // Environment variables the loaders and the device read: set before any other thread runs.
    set_limits(args);
    let output = Output::new(&args.output)?;
    Watchdog::start(
        Duration::from_secs_f64(args.timeout),
        args.input.clone(),
        Arc::clone(&output.state),
    )?;
    check_input(&args.input, args.max_file_mb)?;
    let Ready {
        scene,
        prepared,
        settings,
        installed:
            Installed {
                gpu,
                scene_gpu,
                mut renderer,
                ..
            },
        ..
    } = render_cmd::ready(&render_args(args)?)?;
    let frame_budget = Duration::from_secs_f64(args.timeout / 2.0);
    for i in 0..args.frames {
        if i > 0 && t0.elapsed() > frame_budget {
            log::info!(
                "{} frames in {:.1} s: half of --timeout, no more frames",
                i,
                t0.elapsed().as_secs_f64()
            );
            break;
        }
        renderer.render(&FrameDesc::new(&scene_gpu, scene.f(), prepared.camera, &settings))?;
    }
    let (w, h) = renderer.size();
    let (cw, ch, rgba) = cut_out(&renderer.read_rgba()?, &renderer.read_gbuffer()?, w, h);
    let messages = gpu.validation_messages();
    if messages > 0 {
        log::warn!("the validation layer reported {messages} messages");
    }
    output.commit(cw, ch, &rgba)?;
    log::info!(
        "wrote {} ({cw}×{ch}) in {:.2} s",
        args.output.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Lowers the scene memory limit, the device's and the workers' CPU seconds to the thumbnail's (a lower value
/// already in the environment stays).
fn set_limits(args: &ThumbnailArgs) {
    let cpu_seconds = args.timeout.ceil() as u64 + 1;
    for (var, value) in [
        ("HRTAO_MAX_SCENE_MB", args.max_memory_mb),
        ("HRTAO_DEVICE_MEMORY_LIMIT", args.max_memory_mb * 2 + 512),
        ("HRTAO_OCCT_CPU_SECONDS", cpu_seconds),
        ("HRTAO_IFC_CPU_SECONDS", cpu_seconds),
    ] {
        let current = std::env::var(var).ok().and_then(|v| v.trim().parse::<u64>().ok());
        if current.is_none_or(|c| c > value) {
            std::env::set_var(var, value.to_string());
        }
    }
}

/// A model file within `max_mb` MiB (generator specs have no file).
fn check_input(input: &str, max_mb: u64) -> Result<()> {
    if input.starts_with("gen:") {
        return Ok(());
    }
    let meta = std::fs::metadata(input).with_context(|| format!("cannot read {input}"))?;
    if !meta.is_file() {
        bail!("{input}: not a regular file");
    }
    if meta.len() > max_mb << 20 {
        bail!(
            "{input}: {:.1} MiB, over the thumbnail's limit of {max_mb} MiB (--max-file-mb)",
            meta.len() as f64 / (1 << 20) as f64
        );
    }
    Ok(())
}

/// `hrtao render --scene INPUT --width N --height N --frames F` with the thumbnail's device options.
fn render_args(args: &ThumbnailArgs) -> Result<RenderArgs> {
    let matches = RenderArgs::augment_args(clap::Command::new("render"))
        .try_get_matches_from(["render"])
        .map_err(|e| anyhow!("{e}"))?;
    let mut r = RenderArgs::from_arg_matches(&matches).map_err(|e| anyhow!("{e}"))?;
    r.scene = Some(args.input.clone());
    r.width = Some(args.size);
    r.height = Some(args.size);
    r.frames = args.frames;
    r.ao.mode = args.mode;
    r.device = args.device.clone();
    Ok(r)
}

/// The shaded image cut to the model: the pixels where a primary ray hit it opaque, the rest transparent, cropped
/// to their rectangle with a margin of 1/32 of the image's longest side (at least a pixel). A view that shows
/// nothing of the model (a camera file looking away) is kept whole and opaque.
fn cut_out(rgba: &[u8], gbuffer: &[GPixel], w: u32, h: u32) -> (u32, u32, Vec<u8>) {
    let covered = |p: &GPixel| p.t >= 0.0 && p.instance != NO_INSTANCE;
    let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
    for (i, p) in gbuffer.iter().enumerate() {
        if covered(p) {
            let (x, y) = (i as u32 % w, i as u32 / w);
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
        }
    }
    if x0 > x1 {
        return (w, h, rgba.to_vec());
    }
    let margin = (w.max(h) / 32).max(1);
    let (x0, y0) = (x0.saturating_sub(margin), y0.saturating_sub(margin));
    let (x1, y1) = ((x1 + margin).min(w - 1), (y1 + margin).min(h - 1));
    let (cw, ch) = (x1 - x0 + 1, y1 - y0 + 1);
    let mut out = Vec::with_capacity((cw * ch * 4) as usize);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let i = (y * w + x) as usize;
            let [r, g, b, _] = [rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2], rgba[4 * i + 3]];
            out.extend_from_slice(&[r, g, b, if covered(&gbuffer[i]) { 255 } else { 0 }]);
        }
    }
    (cw, ch, out)
}

/// Where the run is: a timed-out run may remove the temporary file and end only while still working.
#[derive(PartialEq)]
enum Phase {
    Working,
    Done,
}

/// OUTPUT and the temporary file beside it that becomes OUTPUT at the end.
struct Output {
    path: PathBuf,
    tmp: PathBuf,
    state: Arc<Mutex<(Phase, PathBuf)>>,
}

impl Output {
    fn new(path: &Path) -> Result<Output> {
        let name = path
            .file_name()
            .ok_or_else(|| anyhow!("{}: not a file name", path.display()))?;
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() {
            bail!("{}: no such folder", dir.display());
        }
        // Ends with .png: the PNG encoder goes by the extension.
        let tmp = dir.join(format!(
            ".{}.hrtao-{}.png",
            name.to_string_lossy(),
            std::process::id()
        ));
        Ok(Output {
            path: path.to_path_buf(),
            tmp: tmp.clone(),
            state: Arc::new(Mutex::new((Phase::Working, tmp))),
        })
    }

    /// Writes the PNG to the temporary file and renames it onto OUTPUT, holding the watchdog off meanwhile.
    fn commit(&self, w: u32, h: u32, rgba: &[u8]) -> Result<()> {
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let written = hrtao_core::imageio::write_png(&self.tmp, w, h, rgba)
            .map_err(anyhow::Error::from)
            .and_then(|()| {
                std::fs::rename(&self.tmp, &self.path)
                    .with_context(|| format!("cannot write {}", self.path.display()))
            });
        if written.is_err() {
            let _ = std::fs::remove_file(&self.tmp);
        }
        state.0 = Phase::Done;
        written
    }
}

/// Ends the process after the timeout unless the output was committed.
struct Watchdog;

impl Watchdog {
    fn start(timeout: Duration, input: String, state: Arc<Mutex<(Phase, PathBuf)>>) -> Result<()> {
        std::thread::Builder::new()
            .name("thumbnail-watchdog".into())
            .spawn(move || {
                std::thread::sleep(timeout);
                let state = state.lock().unwrap_or_else(|e| e.into_inner());
                if state.0 == Phase::Working {
                    let _ = std::fs::remove_file(&state.1);
                    eprintln!(
                        "hrtao: error: {input}: no thumbnail within {:.1} s (--timeout)",
                        timeout.as_secs_f64()
                    );
                    // At once, without destructors or exit handlers: the main thread may be inside the driver.
                    // The STEP/IFC workers die with this process (PR_SET_PDEATHSIG).
                    unsafe { libc::_exit(1) };
                }
            })
            .context("cannot start the thumbnail's watchdog")?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pixel(hit: bool) -> GPixel {
        GPixel {
            t: if hit { 1.0 } else { -1.0 },
            instance: if hit { 0 } else { NO_INSTANCE },
            ..Default::default()
        }
    }

    #[test]
    fn the_cut_out_keeps_the_model_and_a_margin_transparent_around_it() {
        // 64 × 32, the model a 4 × 2 block at (30, 10): margin 2.
        let (w, h) = (64, 32);
        let g: Vec<GPixel> = (0..w * h)
            .map(|i| pixel((30..34).contains(&(i % w)) && (10..12).contains(&(i / w))))
            .collect();
        let rgba = vec![100u8; (w * h * 4) as usize];
        let (cw, ch, out) = cut_out(&rgba, &g, w, h);
        assert_eq!((cw, ch), (8, 6));
        let alpha: Vec<u8> = out.chunks(4).map(|p| p[3]).collect();
        assert_eq!(alpha.iter().filter(|&&a| a == 255).count(), 8);
        assert_eq!(alpha[0], 0);
        assert_eq!(alpha[2 * 8 + 2], 255);
        // Nothing in view: the whole image.
        let none = vec![pixel(false); (w * h) as usize];
        assert_eq!(cut_out(&rgba, &none, w, h).0, w);
    }
}
