//! `hrtao occt-worker FORMAT RELATIVE ABSOLUTE ANGULAR_DEG PATH`: the process in which OpenCASCADE reads and
//! tessellates a STEP or IGES file, started by the scene loader (`hrtao_scene`'s `cad_load`), never by users.
//!
//! A crash, endless loop or runaway allocation inside the kernel ends this process, not the viewer. The loader
//! sets its address-space and CPU-time limits and has it killed when the viewer dies; here it raises its own OOM
//! score above the viewer's, moves OCCT's console messages (written to stdout) to stderr, and streams frames
//! ([`hrtao_scene::cad`]) on a duplicate of the original stdout: progress, then the model or an error. When the
//! loader stops reading (Cancel), the next progress frame fails and OCCT's user break stops the kernel.

use std::ffi::OsString;

/// The hidden subcommand's name.
pub const SUBCOMMAND: &str = "occt-worker";

/// OOM score added to the worker's (the viewer's is 0): under memory pressure the kernel goes first.
const OOM_SCORE_ADJ: &str = "500";

/// Sets the STEP/IGES tessellation of this process's loads from the command line's `--deflection`,
/// `--deflection-mm` and `--angular-deflection` (each a finite number > 0; unset keeps the default).
pub fn set_tessellation(
    relative: Option<f64>,
    mm: Option<f64>,
    angular_deg: Option<f64>,
) -> Result<(), String> {
    let check = |v: Option<f64>, what: &str| match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(format!("{what} must be a number > 0, got {x}")),
        _ => Ok(v),
    };
    let (relative, mm) = (check(relative, "--deflection")?, check(mm, "--deflection-mm")?);
    let angular_deg = check(angular_deg, "--angular-deflection")?;
    if relative.is_none() && mm.is_none() && angular_deg.is_none() {
        return Ok(());
    }
    let mut t = hrtao_scene::CadTessellation::default();
    if let Some(r) = relative {
        t.relative = r;
    }
    if let Some(mm) = mm {
        (t.relative, t.absolute) = (0.0, mm);
    }
    if let Some(a) = angular_deg {
        t.angular_deg = a.min(90.0);
    }
    hrtao_scene::set_default_cad_tessellation(t);
    Ok(())
}

/// Runs the worker; returns the process exit code.
pub fn main(args: Vec<OsString>) -> i32 {
    let _ = std::fs::write("/proc/self/oom_score_adj", OOM_SCORE_ADJ);
    // SAFETY: plain descriptor calls at start-up, before any other thread exists.
    let frames_fd = unsafe {
        let fd = libc::dup(1);
        libc::dup2(2, 1);
        fd
    };
    if frames_fd < 0 {
        eprintln!("hrtao occt-worker: cannot duplicate stdout");
        return 2;
    }
    // SAFETY: frames_fd is a fresh descriptor owned by this File from now on.
    let file = unsafe { <std::fs::File as std::os::fd::FromRawFd>::from_raw_fd(frames_fd) };
    let mut out = std::io::BufWriter::new(file);
    let result = run(&args, &mut out);
    let sent = match result {
        Ok(model) => hrtao_scene::cad::write_model(&mut out, &model),
        Err(message) => hrtao_scene::cad::write_error(&mut out, &message),
    };
    i32::from(sent.is_err())
}

#[cfg(feature = "occt")]
fn run(args: &[OsString], out: &mut impl std::io::Write) -> Result<hrtao_scene::cad::CadModel, String> {
    let [format, relative, absolute, angular, path] = args else {
        return Err(format!(
            "usage: hrtao {SUBCOMMAND} step|iges RELATIVE ABSOLUTE ANGULAR_DEG PATH (got {} arguments)",
            args.len()
        ));
    };
    let format = match format.to_str() {
        Some("step") => hrtao_occt::Format::Step,
        Some("iges") => hrtao_occt::Format::Iges,
        other => return Err(format!("unknown format {other:?}")),
    };
    let num = |a: &OsString, what: &str| {
        a.to_str()
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|v| v.is_finite() && *v >= 0.0)
            .ok_or_else(|| format!("{what} must be a number >= 0, got {a:?}"))
    };
    let tess = hrtao_occt::Tessellation {
        relative: num(relative, "the relative deflection")?,
        absolute: num(absolute, "the absolute deflection")?,
        angular: num(angular, "the angular deflection")?
            .clamp(0.5, 90.0)
            .to_radians(),
    };
    let mut last = (String::new(), -1.0f64);
    let mut progress = |stage: &str, fraction: f64| {
        // At most ~100 frames per stage; a failed write means the loader is gone: stop the kernel.
        if stage == last.0 && fraction - last.1 < 0.01 && fraction < 1.0 {
            return false;
        }
        last = (stage.to_string(), fraction);
        hrtao_scene::cad::write_progress(out, stage, fraction).is_err()
    };
    hrtao_occt::read(std::path::Path::new(path), format, &tess, &mut progress).map_err(|e| match e {
        hrtao_occt::Error::Kernel(m) => m,
        hrtao_occt::Error::Stopped => "stopped".into(),
    })
}

#[cfg(not(feature = "occt"))]
fn run(_args: &[OsString], _out: &mut impl std::io::Write) -> Result<hrtao_scene::cad::CadModel, String> {
    Err("this hrtao was built without the `occt` feature: STEP and IGES need it (cargo build --features occt, \
         after scripts/install-deps.sh)"
        .into())
}
