//! Ablation of our additions to the paper's technique (a development tool): for one configuration (a name and
//! `AoSettings` overrides on top of the default settings or the paper's mode) and the views of
//! `$HRTAO_SHARED/refs/index.json`, one-frame and N-frame MAE against the Cycles references, still flicker,
//! first-frame cost and navigation cost, written to `OUT/NAME.json`.
//!
//! `HRTAO_SHARED=DIR cargo run --release -p hrtao-core --example ablation -- --name NAME [--base default|paper]
//! [--set '{"refine": false}'] [--out docs/bench/ablation] [--size 640x360] [--rays 8] [--frames 32] [--nav 8]
//! [--nav-deg 0.25] [KEY...]` (keys default to every view of the index).
//!
//! `... --example ablation -- --configs` lists the configurations (`scripts/ablation.sh` runs them).
//!
//! `... --example ablation -- --report docs/bench/ablation` prints the Markdown table of the configurations
//! found there, each metric's change against its reference (`default`, or `paper` for configurations on the
//! paper's base) and the verdict of the rule in `verdict`.
mod cli_args;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use hrtao_core::stats::median;
use hrtao_core::{metrics, AoSettings, Camera, ContextOptions, FrameDesc, Gpu, Mode, Renderer, SceneGpu};
use serde::{Deserialize, Serialize};

/// The quality and cost of one configuration on one view.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
struct SceneMetrics {
    /// AO radius of the view (index.json).
    radius: f32,
    /// MAE of the first frame from an empty map, and after `frames` still frames.
    mae_1: f64,
    mae_n: f64,
    /// Mean |ΔAO| between consecutive still frames from the fifth frame on.
    flicker: f64,
    /// The first frame's wall and GPU milliseconds (`FrameReport::wall_ms`, `gpu_total_ms`).
    first_wall_ms: f64,
    first_gpu_ms: f64,
    /// Medians over the still frames after the first.
    still_wall_ms: f64,
    still_gpu_ms: f64,
    /// Medians over the navigation frames (the camera orbiting its target, `nav_deg` per frame).
    nav_wall_ms: f64,
    nav_gpu_ms: f64,
    /// Rays traced in the first frame.
    first_rays: u64,
    /// The same costs in CPU milliseconds of the process (all its threads, so lavapipe's work too): on a
    /// shared CPU they vary far less with the other processes' load than the wall or timestamp time.
    #[serde(default)]
    first_cpu_ms: f64,
    #[serde(default)]
    still_cpu_ms: f64,
    #[serde(default)]
    nav_cpu_ms: f64,
}

/// One configuration's file, `NAME.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Run {
    name: String,
    /// `default` or `paper`: the settings the overrides apply to.
    base: String,
    overrides: serde_json::Value,
    /// The settings rendered with (`ao_radius` is each scene's), as JSON: runs of older code have other fields.
    settings: serde_json::Value,
    date: String,
    commit: String,
    size: String,
    rays: u32,
    frames: u32,
    nav_frames: u32,
    nav_deg: f32,
    scenes: BTreeMap<String, SceneMetrics>,
}

/// The folder holding `scenes/` and `refs/index.json`: `$HRTAO_SHARED`.
fn shared_root() -> anyhow::Result<PathBuf> {
    std::env::var_os("HRTAO_SHARED")
        .map(PathBuf::from)
        .context("set HRTAO_SHARED=DIR, the folder of scenes/ and refs/index.json")
}

/// `cam` with its eye turned about `cam.up` through its target by `deg` degrees.
fn orbit(cam: &Camera, deg: f32) -> Camera {
    let axis = glam::Vec3::from(cam.up).normalize_or_zero();
    if axis == glam::Vec3::ZERO {
        return *cam;
    }
    let t = glam::Vec3::from(cam.target);
    let q = glam::Quat::from_axis_angle(axis, deg.to_radians());
    Camera {
        eye: (t + q * (glam::Vec3::from(cam.eye) - t)).to_array(),
        ..*cam
    }
}

/// `YYYY-MM-DD HH:MM UTC` now (days to civil date, H. Hinnant's algorithm).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let (days, rem) = (secs.div_euclid(86400), secs.rem_euclid(86400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60
    )
}

/// CPU milliseconds the process has used (user and system, all threads); 0 where unsupported.
fn cpu_ms() -> f64 {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: getrusage writes the struct it is given.
        let mut u: libc::rusage = unsafe { std::mem::zeroed() };
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } == 0 {
            let ms = |t: libc::timeval| t.tv_sec as f64 * 1e3 + t.tv_usec as f64 * 1e-3;
            return ms(u.ru_utime) + ms(u.ru_stime);
        }
    }
    0.0
}

fn git_commit() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}

struct Options {
    size: String,
    frames: u32,
    nav_frames: u32,
    nav_deg: f32,
}

/// Renders one view with `settings` (its radius set here) from a new renderer: still frames, then navigation.
fn measure(
    gpu: &std::sync::Arc<Gpu>,
    root: &Path,
    key: &str,
    entry: &serde_json::Value,
    settings: &AoSettings,
    o: &Options,
) -> anyhow::Result<SceneMetrics> {
    let file = entry["scene"].as_str().context("index entry without a scene")?;
    let radius = entry["radius"].as_f64().context("index entry without a radius")? as f32;
    let scene = hrtao_scene::load(root.join(file).to_str().unwrap(), &mut |_| {})?;
    let cam = Camera::load_in(
        &root.join(format!("refs/{key}_{}.camera.json", o.size)),
        scene.origin,
    )?;
    let (rw, rh, reference) =
        hrtao_core::imageio::read_exr(&root.join(format!("refs/{key}_{}.cycles.exr", o.size)))?;
    anyhow::ensure!(
        (rw, rh) == (cam.width, cam.height),
        "{key}: reference {rw}x{rh}, camera {}x{}",
        cam.width,
        cam.height
    );
    let sg = SceneGpu::new(gpu, &scene)?;
    let settings = settings.clone().with_radius(radius);
    let mut r = Renderer::new(gpu)?;
    let mut m = SceneMetrics {
        radius,
        ..Default::default()
    };
    let (mut still_wall, mut still_gpu, mut still_cpu) = (Vec::new(), Vec::new(), Vec::new());
    let mut prev: Vec<f32> = Vec::new();
    let (mut flicker, mut flicker_n) = (0.0f64, 0u32);
    for f in 0..o.frames {
        let cpu = cpu_ms();
        let rep = r.render(&FrameDesc::new(&sg, scene.f(), cam, &settings))?;
        let cpu = cpu_ms() - cpu;
        if f == 0 {
            m.first_wall_ms = rep.wall_ms;
            m.first_gpu_ms = rep.gpu_total_ms;
            m.first_cpu_ms = cpu;
            m.first_rays = rep.rays;
        } else {
            still_wall.push(rep.wall_ms);
            still_gpu.push(rep.gpu_total_ms);
            still_cpu.push(cpu);
        }
        let ao = r.read_ao()?;
        if f == 0 {
            m.mae_1 = metrics::ao_error(&ao, &reference).mae;
        }
        if f >= 4 {
            let d: f64 = ao.iter().zip(&prev).map(|(a, b)| (a - b).abs() as f64).sum();
            flicker += d / ao.len() as f64;
            flicker_n += 1;
        }
        prev = ao;
    }
    m.mae_n = metrics::ao_error(&prev, &reference).mae;
    m.flicker = flicker / flicker_n.max(1) as f64;
    m.still_wall_ms = median(&still_wall);
    m.still_gpu_ms = median(&still_gpu);
    m.still_cpu_ms = median(&still_cpu);
    let (mut nav_wall, mut nav_gpu, mut nav_cpu) = (Vec::new(), Vec::new(), Vec::new());
    for i in 1..=o.nav_frames {
        let cam = orbit(&cam, o.nav_deg * i as f32);
        let cpu = cpu_ms();
        let rep = r.render(&FrameDesc::new(&sg, scene.f(), cam, &settings))?;
        nav_cpu.push(cpu_ms() - cpu);
        nav_wall.push(rep.wall_ms);
        nav_gpu.push(rep.gpu_total_ms);
    }
    m.nav_wall_ms = median(&nav_wall);
    m.nav_gpu_ms = median(&nav_gpu);
    m.nav_cpu_ms = median(&nav_cpu);
    Ok(m)
}

fn run(mut args: cli_args::Args) -> anyhow::Result<()> {
    let name = args.take("--name", "");
    anyhow::ensure!(!name.is_empty(), "--name NAME is required");
    let base_name = args.take("--base", "default");
    let overrides = args.take("--set", "{}");
    let out = PathBuf::from(args.take("--out", "docs/bench/ablation"));
    let rays: u32 = args.take("--rays", "8").parse()?;
    let o = Options {
        size: args.take("--size", "640x360"),
        frames: args.take("--frames", "32").parse()?,
        nav_frames: args.take("--nav", "8").parse()?,
        nav_deg: args.take("--nav-deg", "0.25").parse()?,
    };
    anyhow::ensure!(o.frames >= 1, "--frames must be at least 1");
    let base = match base_name.as_str() {
        "default" => AoSettings::default(),
        "paper" => AoSettings::default().paper(),
        b => anyhow::bail!("--base {b:?}: default or paper"),
    };
    let mut settings = cli_args::with_overrides(&base, &overrides)?;
    settings.map.rays_per_pixel = rays;
    settings.display.mode = Mode::Hrtao;
    let root = shared_root()?;
    let index_path = root.join("refs/index.json");
    let index: serde_json::Map<String, serde_json::Value> = serde_json::from_str(
        &std::fs::read_to_string(&index_path).with_context(|| format!("reading {}", index_path.display()))?,
    )?;
    let keys: Vec<String> = if args.0.is_empty() {
        index.keys().cloned().collect()
    } else {
        args.0.clone()
    };
    let gpu = Gpu::new(&ContextOptions::default())?;
    let mut scenes = BTreeMap::new();
    for key in &keys {
        let entry = index
            .get(key)
            .with_context(|| format!("no view {key:?} in {}", index_path.display()))?;
        let t = std::time::Instant::now();
        let m = measure(&gpu, &root, key, entry, &settings, &o)?;
        eprintln!(
            "{name} {key}: 1f {:.4}, {}f {:.4}, flicker {:.5}, first {:.0} ms ({:.0} CPU), nav {:.0} ms ({:.0} CPU) ({:.0} s)",
            m.mae_1,
            o.frames,
            m.mae_n,
            m.flicker,
            m.first_wall_ms,
            m.first_cpu_ms,
            m.nav_wall_ms,
            m.nav_cpu_ms,
            t.elapsed().as_secs_f64()
        );
        scenes.insert(key.clone(), m);
    }
    let run = Run {
        name: name.clone(),
        base: base_name,
        overrides: serde_json::from_str(&overrides)?,
        settings: serde_json::to_value(&settings)?,
        date: utc_now(),
        commit: git_commit(),
        size: o.size,
        rays,
        frames: o.frames,
        nav_frames: o.nav_frames,
        nav_deg: o.nav_deg,
        scenes,
    };
    // A run killed midway leaves no NAME.json: write a temporary file, then rename it.
    std::fs::create_dir_all(&out)?;
    let path = out.join(format!("{name}.json"));
    let tmp = out.join(format!(".{name}.json.tmp"));
    std::fs::write(&tmp, serde_json::to_string_pretty(&run)? + "\n")?;
    std::fs::rename(&tmp, &path)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------
// The report: relative changes and the verdicts.

/// The metrics the table shows, in its column order: (field, label, cost).
const METRICS: [(&str, &str, bool); 5] = [
    ("mae_1", "1f", false),
    ("mae_n", "32f", false),
    ("flicker", "flicker", false),
    ("first", "first ms", true),
    ("nav", "nav ms", true),
];

/// Quality worsening that counts (3 %), cost saving that counts (5 %), scenes it must hold on (3).
const QUALITY_THRESHOLD: f64 = 0.03;
const COST_THRESHOLD: f64 = 0.05;
const MIN_SCENES: usize = 3;

/// The clock costs are read on: the process's CPU time when every run measured it, else the GPU timestamps
/// when every run has them, else the wall clock.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Clock {
    Cpu,
    Gpu,
    Wall,
}

fn value(m: &SceneMetrics, metric: &str, clock: Clock) -> f64 {
    match (metric, clock) {
        ("mae_1", _) => m.mae_1,
        ("mae_n", _) => m.mae_n,
        ("flicker", _) => m.flicker,
        ("first", Clock::Cpu) => m.first_cpu_ms,
        ("first", Clock::Gpu) => m.first_gpu_ms,
        ("first", Clock::Wall) => m.first_wall_ms,
        ("nav", Clock::Cpu) => m.nav_cpu_ms,
        ("nav", Clock::Gpu) => m.nav_gpu_ms,
        ("nav", Clock::Wall) => m.nav_wall_ms,
        _ => unreachable!("unknown metric {metric}"),
    }
}

/// `a / b - 1` (0 when `b` is 0).
fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        0.0
    } else {
        a / b - 1.0
    }
}

/// The configuration a row is compared with, and whether the row turns an addition on (else off).
fn role(run: &Run) -> Option<(&'static str, bool)> {
    match run.name.as_str() {
        "default" | "default-rerun" | "paper" => None,
        n => Some((
            if run.base == "paper" { "paper" } else { "default" },
            n.starts_with("with-") || n.starts_with("paper+"),
        )),
    }
}

/// The addition's verdict from the pair (`off`, `on`): the configurations without and with it.
/// `spread[metric][scene]` is the run-to-run |relative difference|. Keep when turning it off worsens
/// one-frame MAE, N-frame MAE or flicker by at least max(3 %, spread) on at least 3 scenes (one metric), or
/// raises the first-frame or navigation cost by at least max(5 %, spread) on at least 3 scenes.
#[derive(Debug, PartialEq)]
struct Verdict {
    keep: bool,
    /// Per metric, the scenes where turning the addition off crosses the threshold.
    counts: Vec<(&'static str, usize)>,
}

fn verdict(off: &Run, on: &Run, spread: &BTreeMap<(&str, String), f64>, clock: Clock) -> Verdict {
    let mut counts = Vec::new();
    let mut keep = false;
    for (metric, label, cost) in METRICS {
        let threshold = if cost { COST_THRESHOLD } else { QUALITY_THRESHOLD };
        let n = on
            .scenes
            .iter()
            .filter_map(|(key, m_on)| off.scenes.get(key).map(|m_off| (key, m_on, m_off)))
            .filter(|(key, m_on, m_off)| {
                let s = spread.get(&(metric, (*key).clone())).copied().unwrap_or(0.0);
                rel(value(m_off, metric, clock), value(m_on, metric, clock)) >= threshold.max(s)
            })
            .count();
        keep |= n >= MIN_SCENES;
        counts.push((label, n));
    }
    Verdict { keep, counts }
}

fn load_runs(dir: &Path) -> anyhow::Result<Vec<Run>> {
    let mut runs = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let p = e?.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name.ends_with(".json") && !name.starts_with('.') {
            let text = std::fs::read_to_string(&p)?;
            runs.push(serde_json::from_str(&text).with_context(|| format!("reading {}", p.display()))?);
        }
    }
    Ok(runs)
}

/// The row order: the baselines, then the "off" rows, then the rows on the paper's base; by name within.
fn order(run: &Run) -> (u32, String) {
    let rank = match (run.name.as_str(), role(run)) {
        ("default", _) => 0,
        ("default-rerun", _) => 1,
        ("paper", _) => 2,
        (_, Some(("default", _))) => 3,
        _ => 4,
    };
    (rank, run.name.clone())
}

fn pct(x: f64) -> String {
    format!("{:+.1}", 100.0 * x)
}

fn report(runs: &[Run]) -> String {
    let mut runs: Vec<&Run> = runs.iter().collect();
    runs.sort_by_key(|r| order(r));
    let by_name: BTreeMap<&str, &Run> = runs.iter().map(|r| (r.name.as_str(), *r)).collect();
    let mut keys: Vec<String> = Vec::new();
    for r in &runs {
        for k in r.scenes.keys() {
            if !keys.contains(k) {
                keys.push(k.clone());
            }
        }
    }
    let preferred = ["rod", "cycloidal", "engine", "duplex", "sf"];
    keys.sort_by_key(|k| preferred.iter().position(|p| p == k).unwrap_or(preferred.len()));
    let all = |f: fn(&SceneMetrics) -> bool| runs.iter().all(|r| r.scenes.values().all(f));
    let clock = if all(|m| m.first_cpu_ms > 0.0 && m.nav_cpu_ms > 0.0) {
        Clock::Cpu
    } else if all(|m| m.first_gpu_ms > 0.0 && m.nav_gpu_ms > 0.0) {
        Clock::Gpu
    } else {
        Clock::Wall
    };
    let mut spread = BTreeMap::new();
    if let (Some(a), Some(b)) = (by_name.get("default"), by_name.get("default-rerun")) {
        for (metric, _, _) in METRICS {
            for (key, ma) in &a.scenes {
                if let Some(mb) = b.scenes.get(key) {
                    let s = rel(value(mb, metric, clock), value(ma, metric, clock)).abs();
                    spread.insert((metric, key.clone()), s);
                }
            }
        }
    }
    let labels: Vec<&str> = METRICS.iter().map(|m| m.1).collect();
    let mut out = String::new();
    out += &format!(
        "Each cell: {} ({} costs), relative change in % against the row's reference; \
         absolute values on the reference rows (MAE and flicker ×1000, ms).\n\n",
        labels.join(" / "),
        match clock {
            Clock::Cpu => "CPU",
            Clock::Gpu => "GPU",
            Clock::Wall => "wall",
        }
    );
    out += &format!("| configuration | vs | {} | verdict |\n", keys.join(" | "));
    out += &format!("|---|---|{}---|\n", "---|".repeat(keys.len()));
    let absolute = |m: &SceneMetrics| {
        METRICS
            .iter()
            .map(|(metric, _, cost)| {
                let v = value(m, metric, clock);
                if *cost {
                    format!("{v:.0}")
                } else {
                    format!("{:.2}", 1000.0 * v)
                }
            })
            .collect::<Vec<_>>()
            .join(" / ")
    };
    for r in &runs {
        let (reference, verdict_text) = match (r.name.as_str(), role(r)) {
            ("default-rerun", _) => (by_name.get("default").copied(), "spread".to_string()),
            (_, None) => (None, String::new()),
            (_, Some((reference, on))) => match by_name.get(reference) {
                Some(refr) => {
                    let (off, on_run) = if on { (*refr, *r) } else { (*r, *refr) };
                    let v = verdict(off, on_run, &spread, clock);
                    let counts: Vec<String> = v.counts.iter().map(|(l, n)| format!("{l} {n}")).collect();
                    let word = if v.keep { "**keep**" } else { "delete" };
                    (Some(*refr), format!("{word} ({})", counts.join(", ")))
                }
                None => (None, format!("(no {reference} run)")),
            },
        };
        let cells: Vec<String> = keys
            .iter()
            .map(
                |k| match (r.scenes.get(k), reference.and_then(|x| x.scenes.get(k))) {
                    (Some(m), Some(mr)) => METRICS
                        .iter()
                        .map(|(metric, _, _)| pct(rel(value(m, metric, clock), value(mr, metric, clock))))
                        .collect::<Vec<_>>()
                        .join(" / "),
                    (Some(m), None) => absolute(m),
                    _ => "–".into(),
                },
            )
            .collect();
        out += &format!(
            "| {} | {} | {} | {} |\n",
            r.name,
            reference.map_or("", |x| x.name.as_str()),
            cells.join(" | "),
            verdict_text
        );
    }
    out += &format!(
        "\nVerdict (on the rows that turn one addition off on the default, or on on the paper's mode): \
         keep when the configuration without the addition has a one-frame MAE, {}-frame MAE or flicker worse by \
         ≥ max(3 %, spread) on ≥ 3 scenes (one metric), or a first-frame or navigation cost higher by \
         ≥ max(5 %, spread) on ≥ 3 scenes; the counts are the scenes per metric. Spread: |default-rerun / \
         default − 1| per metric and scene.\n",
        runs.first().map_or(32, |r| r.frames)
    );
    out
}

/// The configurations, one `name|base|overrides` line each: the baselines, then every addition of ours
/// (`AoSettings::additions_mut`) off on the default settings and alone on the paper's mode. Derived from the
/// settings, so adding or deleting an addition does not touch the ablation's script.
fn configs() -> String {
    let mut out = String::from("default|default|{}\ndefault-rerun|default|{}\npaper|paper|{}\n");
    let mut s = AoSettings::default();
    let names: Vec<&str> = s.additions_mut().iter().map(|a| a.name).collect();
    for (prefix, base, on) in [("no-", "default", false), ("paper+", "paper", true)] {
        for name in &names {
            let row = name.replace('_', "-");
            out += &format!("{prefix}{row}|{base}|{}\n", serde_json::json!({ *name: on }));
        }
    }
    out
}

fn main() -> anyhow::Result<()> {
    let mut args = cli_args::Args::from_env();
    if std::env::args().any(|a| a == "--configs") {
        print!("{}", configs());
        return Ok(());
    }
    let dir = args.take("--report", "");
    if !dir.is_empty() {
        let runs = load_runs(Path::new(&dir))?;
        anyhow::ensure!(!runs.is_empty(), "no configuration JSON in {dir}");
        print!("{}", report(&runs));
        return Ok(());
    }
    run(args)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(mae_1: f64, mae_n: f64, flicker: f64, first: f64, nav: f64) -> SceneMetrics {
        SceneMetrics {
            mae_1,
            mae_n,
            flicker,
            first_wall_ms: first,
            nav_wall_ms: nav,
            ..Default::default()
        }
    }

    fn run(name: &str, base: &str, scenes: [SceneMetrics; 5]) -> Run {
        Run {
            name: name.into(),
            base: base.into(),
            overrides: serde_json::json!({}),
            settings: serde_json::to_value(AoSettings::default()).unwrap(),
            date: String::new(),
            commit: String::new(),
            size: "640x360".into(),
            rays: 8,
            frames: 32,
            nav_frames: 8,
            nav_deg: 0.25,
            scenes: ["rod", "cycloidal", "engine", "duplex", "sf"]
                .into_iter()
                .map(String::from)
                .zip(scenes)
                .collect(),
        }
    }

    fn base() -> [SceneMetrics; 5] {
        std::array::from_fn(|_| scene(0.1, 0.05, 0.01, 1000.0, 500.0))
    }

    #[test]
    fn an_addition_whose_removal_worsens_three_scenes_beyond_the_spread_is_kept() {
        let default = run("default", "default", base());
        // The rerun differs by 1 % in one-frame MAE on rod: rod's spread.
        let mut rerun_scenes = base();
        rerun_scenes[0].mae_1 = 0.101;
        let rerun = run("default-rerun", "default", rerun_scenes);
        // Off: one-frame MAE 4 % worse on rod, cycloidal and engine (kept); 2 % on the others.
        let mut off = base();
        for (i, s) in off.iter_mut().enumerate() {
            s.mae_1 = if i < 3 { 0.104 } else { 0.102 };
        }
        let off = run("no-x", "default", off);
        let text = report(&[default.clone(), rerun.clone(), off]);
        let row = text.lines().find(|l| l.starts_with("| no-x ")).unwrap();
        assert!(row.contains("**keep** (1f 3, 32f 0, flicker 0"), "{row}");
        assert!(row.contains("| +4.0 / +0.0 / +0.0 / +0.0 / +0.0 |"), "{row}");
        // With rod's spread raised to 5 %, only two scenes count: delete.
        let mut rerun_scenes = base();
        rerun_scenes[0].mae_1 = 0.105;
        let rerun = run("default-rerun", "default", rerun_scenes);
        let mut off = base();
        for (i, s) in off.iter_mut().enumerate() {
            s.mae_1 = if i < 3 { 0.104 } else { 0.102 };
        }
        let text = report(&[default, rerun, run("no-x", "default", off)]);
        let row = text.lines().find(|l| l.starts_with("| no-x ")).unwrap();
        assert!(row.contains("delete (1f 2,"), "{row}");
    }

    #[test]
    fn an_addition_that_only_costs_is_deleted_and_one_that_saves_time_is_kept() {
        let default = run("default", "default", base());
        let rerun = run("default-rerun", "default", base());
        let paper = run("paper", "paper", base());
        // Off is 10 % cheaper on every scene and 1 % better: the addition only costs.
        let mut off = base();
        for s in &mut off {
            s.first_wall_ms = 900.0;
            s.mae_n = 0.0495;
        }
        // Alone on the paper's mode: 6 % less navigation cost on 4 scenes, quality unchanged.
        let mut alone = base();
        for s in alone.iter_mut().take(4) {
            s.nav_wall_ms = 470.0;
        }
        let runs = [
            default,
            rerun,
            paper,
            run("no-y", "default", off),
            run("paper+z", "paper", alone),
        ];
        let text = report(&runs);
        let y = text.lines().find(|l| l.starts_with("| no-y ")).unwrap();
        assert!(
            y.contains("delete (1f 0, 32f 0, flicker 0, first ms 0, nav ms 0)"),
            "{y}"
        );
        let z = text.lines().find(|l| l.starts_with("| paper+z ")).unwrap();
        assert!(
            z.contains("| paper |") && z.contains("**keep**") && z.contains("nav ms 4)"),
            "{z}"
        );
        // Rows are ordered: baselines, off rows, rows on the paper's base.
        let names: Vec<&str> = text
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| configuration"))
            .map(|l| l.split(" | ").next().unwrap().trim_start_matches("| "))
            .collect();
        assert_eq!(names, ["default", "default-rerun", "paper", "no-y", "paper+z"]);
    }

    #[test]
    fn costs_are_read_on_the_cpu_clock_when_every_run_has_it() {
        // Wall clock: 20 % dearer without the addition; CPU clock: the same. CPU wins, so no cost verdict.
        let with_cpu = |first_cpu: f64| {
            let mut s = base();
            for m in &mut s {
                m.first_cpu_ms = first_cpu;
                m.nav_cpu_ms = 400.0;
            }
            s
        };
        let mut off = with_cpu(800.0);
        for m in &mut off {
            m.first_wall_ms = 1200.0;
        }
        let runs = [
            run("default", "default", with_cpu(800.0)),
            run("no-w", "default", off.clone()),
        ];
        let text = report(&runs);
        assert!(text.contains("(CPU costs)"), "{text}");
        assert!(
            text.contains("delete (1f 0, 32f 0, flicker 0, first ms 0, nav ms 0)"),
            "{text}"
        );
        // One run without CPU times: the wall clock for all, and the 20 % counts on every scene.
        let runs = [run("default", "default", base()), run("no-w", "default", off)];
        let text = report(&runs);
        assert!(
            text.contains("(wall costs)") && text.contains("**keep** ("),
            "{text}"
        );
        assert!(text.contains("first ms 5,"), "{text}");
    }

    #[test]
    fn the_orbit_turns_about_the_up_axis() {
        let cam = Camera {
            eye: [1.0, 0.0, 0.0],
            target: [0.0; 3],
            up: [0.0, 0.0, 1.0],
            ..Default::default()
        };
        let e = orbit(&cam, 90.0).eye;
        assert!(
            (e[0]).abs() < 1e-6 && (e[1] - 1.0).abs() < 1e-6 && e[2].abs() < 1e-6,
            "{e:?}"
        );
    }
}
