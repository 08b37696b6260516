//! `hrtao bench`: the paper's Tables 1 and 2 on this device, HRTAO against per-pixel RTAO in the same run, and error
//! against a converged reference, written as JSON (`hrtao_core::bench_json`; `cargo run -p bench-report` turns a
//! directory of results into `docs/benchmarks.md`).
//!
//! One run: load + build (timed), warm-up, then
//! 1. timing: HRTAO first frame (`--repeat` times from an empty cache, medians) and navigation frames along
//!    `--path` or an orbit; per-pixel RTAO at the same B over the same cameras (its first frame is the raw
//!    AO-ray throughput measure: primary + B AO rays, no hashing);
//! 2. quality (unless `--no-quality`): one progressive per-pixel RTAO run of `step` rays per frame; its first
//!    `max_rays` samples give the RTAO error curve and the samples after them form the converged reference (no
//!    sample shared with the estimates); HRTAO from an empty cache for `--hrtao-frames` static frames gives its
//!    curve; the per-pixel rays matching HRTAO's one-frame error are interpolated on the RTAO curve.
pub mod stats;

use std::collections::BTreeMap;

use anyhow::{bail, Context, Result};
use hrtao_core::bench_json::{
    BenchResult, CurvePoint, ExternalErrors, FrameRecord, HostInfo, HrtaoPoint, Match, Memory, ModeRun,
    Quality, SceneInfo, Summary, NON_RAY_PASSES, SCHEMA,
};
use hrtao_core::metrics::{ao_error, AoError};
use hrtao_core::{imageio, AoSettings, Camera, FrameDesc, Mode, Renderer, SceneGpu};

use crate::cli::BenchArgs;
use crate::common::{load_scene, write_json};
use crate::setup::{self, Device, Installed, SetupInputs};
use stats::{rays_to_reach, segment_mean};

/// Navigation cameras from a path file: a JSON array of cameras or {"cameras": [...]}.
pub fn load_path(path: &std::path::Path, width: u32, height: u32) -> Result<Vec<Camera>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let list = match &v {
        serde_json::Value::Array(_) => v.clone(),
        serde_json::Value::Object(o) => o
            .get("cameras")
            .or_else(|| o.get("frames"))
            .cloned()
            .context("path file: expected an array of cameras or {\"cameras\": [...]}")?,
        _ => bail!("path file: expected an array of cameras"),
    };
    let cams: Vec<Camera> =
        serde_json::from_value(list).with_context(|| format!("{}: bad camera entries", path.display()))?;
    if cams.is_empty() {
        bail!("{}: the path has no camera", path.display());
    }
    cams.into_iter()
        .enumerate()
        .map(|(i, c)| {
            let c = Camera { width, height, ..c };
            c.validate()
                .map_err(|e| anyhow::anyhow!("{}: camera {i}: {e}", path.display()))?;
            Ok(c)
        })
        .collect()
}

/// `n` cameras orbiting `cam.target` about `cam.up`, `step_deg` apart, starting one step after `cam`.
pub fn orbit_path(cam: &Camera, n: u32, step_deg: f32) -> Vec<Camera> {
    (1..=n)
        .map(|i| Camera {
            eye: stats::orbit_eye(cam.eye, cam.target, cam.up, step_deg * i as f32),
            ..*cam
        })
        .collect()
}

/// A byte count from the allocator counter that is not 0 and has not wrapped below zero.
fn sane_bytes(b: u64) -> bool {
    b > 0 && b < 1 << 48
}

/// Scene memory from the build statistics: geometry, BLAS, and ~128 bytes per TLAS instance (instance record,
/// per-instance info and the TLAS nodes).
pub fn scene_device_estimate(s: &hrtao_core::accel::BuildStats) -> u64 {
    s.geometry_bytes + s.blas_bytes + s.tlas_instances as u64 * 128
}

/// The renderer's buffers: per-pixel targets and the hash map.
pub fn renderer_device_estimate(w: u32, h: u32, hash_capacity: u32) -> u64 {
    use hrtao_core::gpu::{GPixel, HashCell, PixelCells};
    let n = w as u64 * h as u64;
    n * (std::mem::size_of::<GPixel>() + std::mem::size_of::<PixelCells>() + 10 * 4) as u64
        + hash_capacity as u64 * std::mem::size_of::<HashCell>() as u64
}

fn proc_status_kb(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        })
        .unwrap_or(0)
}

pub fn host_info() -> HostInfo {
    let cpu_model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1).map(|v| v.trim().to_string()))
        })
        .unwrap_or_else(|| "unknown".into());
    HostInfo {
        cpu_cores: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        cpu_model,
    }
}

fn label_of(spec: &str) -> String {
    if spec.starts_with("gen:") {
        return spec.to_string();
    }
    std::path::Path::new(spec)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| spec.to_string())
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let spec = args.scene.as_deref().context("--scene is required")?;
    if args.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    if args.step == 0 {
        bail!("--step must be at least 1");
    }
    let t_bench = std::time::Instant::now();
    let inputs = SetupInputs::from_bench(args);
    let (scene, load_ms) = load_scene(spec)?;
    let prepared = setup::prepare(&inputs, &scene)?;
    let camera = prepared.camera;
    let (w, h) = (camera.width, camera.height);
    let (nav_cams, navigation) = match &args.path {
        Some(p) => (load_path(p, w, h)?, "path".to_string()),
        None => (
            orbit_path(&camera, args.orbit.unwrap_or(16), args.orbit_step),
            "orbit".to_string(),
        ),
    };
    if nav_cams.is_empty() {
        bail!("no navigation frame (--orbit 0)");
    }
    let mut hrtao_settings = args.ao.settings(prepared.radius)?;
    hrtao_settings.display.mode = Mode::Hrtao;
    hrtao_settings.validate().map_err(|e| anyhow::anyhow!(e))?;
    if hrtao_settings.map.rays_per_pixel == 0 {
        bail!("--rays must be at least 1 for a benchmark");
    }
    if args.ao.mode != Mode::Hrtao {
        log::warn!("--mode is ignored: the bench runs HRTAO and per-pixel RTAO side by side");
    }
    let rtao_settings = {
        let mut s = hrtao_settings.clone();
        s.display.mode = Mode::Rtao;
        s
    };

    // Progress by phase: build, warm-up, HRTAO timing, per-pixel RTAO timing, quality.
    let bar = crate::common::progress(if args.no_quality { 4 } else { 5 }, "bench");
    bar.set_message("building");
    let device = Device::open(&args.device)?;
    if !device.gpu.info.timestamps {
        log::warn!("the device has no timestamp queries: GPU times will be zero");
    }
    // Every renderer of the run (ours, the paper's mode, per-pixel RTAO) finds primary visibility the same way,
    // chosen once: the modes differ in their AO only.
    let installed = device.install(&scene, &prepared, &hrtao_settings)?;
    let (device_scene_bytes, device_total_bytes) =
        (installed.scene_device_bytes, installed.total_device_bytes);
    let mut paper_r = installed.another_renderer()?;
    let Installed {
        gpu,
        scene_gpu,
        renderer: mut r,
        primary,
        ..
    } = installed;
    let sections = &prepared.sections;
    let scene_estimate = scene_device_estimate(&scene_gpu.stats);
    let (device_scene_bytes, device_total_bytes, device_bytes_source) =
        if sane_bytes(device_scene_bytes) && sane_bytes(device_total_bytes) {
            (device_scene_bytes, device_total_bytes, "allocator")
        } else {
            log::warn!("the allocator's device byte count is not usable: reporting an estimate");
            let total = scene_estimate + renderer_device_estimate(w, h, hrtao_settings.map.hash_capacity);
            (scene_estimate, total, "estimate")
        };
    let sf = scene.f();

    // The paper's behaviour (our additions off) on a renderer of its own (`paper_r`), so both run side by side.
    let paper_settings = hrtao_settings.paper();

    bar.inc(1);
    bar.set_message("warm-up");
    // Warm-up (pipeline compilation, caches) for every mode.
    let frame = |cam: &Camera, s| FrameDesc::new(&scene_gpu, sf, *cam, s);
    r.render(&frame(&camera, &hrtao_settings))?;
    paper_r.render(&frame(&camera, &paper_settings))?;
    r.render(&frame(&camera, &rtao_settings))?;

    bar.inc(1);
    bar.set_message("HRTAO timing");
    // 1. Timing: HRTAO and the paper's behaviour, frame by frame over the same cameras.
    let [hrtao, paper] = time_hrtao(
        [(&mut r, &hrtao_settings), (&mut paper_r, &paper_settings)],
        &scene_gpu,
        sf,
        &camera,
        &nav_cams,
        args,
    )?;
    drop(paper_r);
    log::info!(
        "HRTAO: first {:.1} ms (passes {:.1} ms), nav {:.1} ms (passes {:.1} ms), GPU medians",
        hrtao.first_stats.gpu_total_ms,
        hrtao.first_stats.hrtao_passes_ms,
        hrtao.nav_stats.gpu_total_ms,
        hrtao.nav_stats.hrtao_passes_ms
    );
    log::info!(
        "HRTAO, the paper's mode: first {:.1} ms, nav {:.1} ms (GPU medians)",
        paper.first_stats.gpu_total_ms,
        paper.nav_stats.gpu_total_ms
    );
    log::info!(
        "navigation, ours / paper's mode frame by frame (median): whole frame {:.3}, primary visibility (the same \
         work in both: the noise) {:.3}",
        hrtao.nav_paired_ratio(&paper, None),
        hrtao.nav_paired_ratio(&paper, Some("primary visibility"))
    );

    bar.inc(1);
    bar.set_message("RTAO timing");
    // Per-pixel RTAO at the same B over the same cameras (no accumulation: each first frame after a reset).
    r.restart_still_image();
    let mut first = Vec::new();
    for i in 0..args.repeat {
        // Repetitions accumulate (same camera), at the same cost per frame: B rays per covered pixel.
        let rep = r.render(&frame(&camera, &rtao_settings))?;
        first.push(FrameRecord::new(i as usize, "first", &rep));
    }
    let mut nav = Vec::new();
    for (i, cam) in nav_cams.iter().enumerate() {
        let rep = r.render(&frame(cam, &rtao_settings))?;
        nav.push(FrameRecord::new(i + 1, "nav", &rep));
    }
    let rtao = ModeRun::new(first, Vec::new(), nav);
    log::info!(
        "per-pixel RTAO: first {:.1} ms, nav {:.1} ms (GPU medians)",
        rtao.first_stats.gpu_total_ms,
        rtao.nav_stats.gpu_total_ms
    );
    let summary = summarize(&hrtao, &rtao);

    bar.inc(1);
    bar.set_message("quality");
    // 2. Quality.
    let quality = if args.no_quality {
        None
    } else {
        Some(measure_quality(
            args,
            &mut r,
            &scene_gpu,
            sf,
            &camera,
            &hrtao_settings,
        )?)
    };

    bar.finish_and_clear();
    let validation_messages = gpu.validation_messages();
    let unix_time = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let result = BenchResult {
        schema: SCHEMA.into(),
        date: stats::utc_date(unix_time),
        unix_time,
        host: host_info(),
        device: serde_json::to_value(&gpu.info)?,
        scene: SceneInfo {
            spec: spec.to_string(),
            label: args.label.clone().unwrap_or_else(|| label_of(spec)),
            group: args.group.name().to_string(),
            meshes: scene.meshes.len(),
            instances: scene.instances.len(),
            unique_triangles: scene.unique_triangle_count(),
            instanced_triangles: scene.instanced_triangle_count(),
            load_ms,
        },
        build: serde_json::to_value(&scene_gpu.stats)?,
        memory: Memory {
            host_rss_bytes: proc_status_kb("VmRSS:") * 1024,
            host_peak_bytes: proc_status_kb("VmHWM:") * 1024,
            device_scene_bytes,
            device_total_bytes,
            device_bytes_source: device_bytes_source.into(),
        },
        width: w,
        height: h,
        camera,
        primary,
        settings: {
            let mut v = serde_json::to_value(&hrtao_settings)?;
            v["sections"] = serde_json::to_value(&sections.planes)?;
            v
        },
        navigation,
        nav_frames: nav_cams.len(),
        hrtao,
        paper: Some(paper),
        rtao,
        summary,
        quality,
        validation_messages,
        total_bench_s: t_bench.elapsed().as_secs_f64(),
    };
    print_summary(&result);
    if let Some(path) = &args.json {
        write_json(path, &result)?;
        log::info!("wrote {}", path.display());
    }
    if validation_messages > 0 {
        log::warn!("the validation layer reported {validation_messages} messages");
    }
    Ok(())
}

/// HRTAO timing of N renderers (ours and the paper's mode, each with its settings), interleaved frame by frame
/// so that a change of load on the machine hits them alike, and in turns in reverse order, so that neither is
/// always the one that runs first after the host's work: the first frame `--repeat` times from an empty map,
/// static frames until each map has settled, then the navigation cameras.
fn time_hrtao<const N: usize>(
    rs: [(&mut Renderer, &AoSettings); N],
    scene_gpu: &SceneGpu,
    sf: u32,
    camera: &Camera,
    nav_cams: &[Camera],
    args: &BenchArgs,
) -> Result<[ModeRun; N]> {
    // The renderers in turn i: forwards, then backwards.
    let turn = |i: usize| -> Vec<usize> {
        if i.is_multiple_of(2) {
            (0..N).collect()
        } else {
            (0..N).rev().collect()
        }
    };
    // One untimed frame of each renderer first: lavapipe compiles a pipeline at its first dispatch (~0.4 s
    // each), which the renderer that happens to use it first would otherwise pay inside its first timed frame.
    // Each timed first frame then starts from an empty map and a new still image (`clear_cache`).
    for k in turn(0) {
        rs[k].0.render(&FrameDesc::new(scene_gpu, sf, *camera, rs[k].1))?;
    }
    let mut first: [Vec<FrameRecord>; N] = std::array::from_fn(|_| Vec::new());
    for i in 0..args.repeat as usize {
        for k in turn(i) {
            rs[k].0.clear_cache()?;
            let rep = rs[k].0.render(&FrameDesc::new(scene_gpu, sf, *camera, rs[k].1))?;
            first[k].push(FrameRecord::new(i, "first", &rep));
        }
    }
    let mut settle: [Vec<FrameRecord>; N] = std::array::from_fn(|_| Vec::new());
    let mut settled = [false; N];
    for i in 0..args.settle {
        for k in 0..N {
            if settled[k] {
                continue;
            }
            let rep = rs[k].0.render(&FrameDesc::new(scene_gpu, sf, *camera, rs[k].1))?;
            settle[k].push(FrameRecord::new(i as usize + 1, "settle", &rep));
            // Settled once the cells take few rays (the still-camera refinement's own rays, which every pixel
            // traces while the view rests, do not count; the cells take some of them).
            let first_rays = first[k].last().map(|f| f.rays).unwrap_or(0) as f64;
            settled[k] = (rep.cell_rays as f64) < args.settle_until * first_rays;
        }
        if settled.iter().all(|&s| s) {
            break;
        }
    }
    let mut nav: [Vec<FrameRecord>; N] = std::array::from_fn(|_| Vec::new());
    for (i, cam) in nav_cams.iter().enumerate() {
        for k in turn(i) {
            let rep = rs[k].0.render(&FrameDesc::new(scene_gpu, sf, *cam, rs[k].1))?;
            nav[k].push(FrameRecord::new(i + 1, "nav", &rep));
        }
    }
    let mut runs = first.into_iter().zip(settle).zip(nav);
    Ok(std::array::from_fn(|_| {
        let ((first, settle), nav) = runs.next().expect("N runs");
        ModeRun::new(first, settle, nav)
    }))
}

pub fn summarize(hrtao: &ModeRun, rtao: &ModeRun) -> Summary {
    let hf = &hrtao.first_stats;
    let hn = &hrtao.nav_stats;
    let rf = &rtao.first_stats;
    let div = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::NAN };
    let rt_update = hf.pass("ray-tracing update");
    let non_ray: f64 = NON_RAY_PASSES.iter().map(|p| hf.pass(p)).sum();
    let raw_ms = rf.pass("primary visibility") + rf.pass("per-pixel RTAO");
    let raw = div(rf.rays, raw_ms);
    let raw_pass = div(rf.rays, rf.pass("per-pixel RTAO"));
    let hr = div(hf.rays, rt_update);
    Summary {
        first_ms: hf.hrtao_passes_ms,
        nav_ms: hn.hrtao_passes_ms,
        nav_over_first: div(hn.hrtao_passes_ms, hf.hrtao_passes_ms),
        first_frame_gpu_ms: hf.gpu_total_ms,
        nav_frame_gpu_ms: hn.gpu_total_ms,
        nav_over_first_frame: div(hn.gpu_total_ms, hf.gpu_total_ms),
        first_wall_ms: hf.wall_ms,
        nav_wall_ms: hn.wall_ms,
        cell_finder_ms: hf.pass("cell finder"),
        ray_tracing_update_ms: rt_update,
        per_pixel_ao_ms: hf.pass("per-pixel AO"),
        filtering_ms: hf.pass("filtering"),
        primary_visibility_ms: hf.pass("primary visibility"),
        non_ray_share: div(non_ray, hf.hrtao_passes_ms),
        non_ray_share_frame: div(
            hf.gpu_total_ms - rt_update - hf.pass("primary visibility"),
            hf.gpu_total_ms,
        ),
        rtao_frame_gpu_ms: rf.gpu_total_ms,
        rtao_nav_frame_gpu_ms: rtao.nav_stats.gpu_total_ms,
        raw_rays_per_ms: raw,
        raw_pass_rays_per_ms: raw_pass,
        hrtao_rays_per_ms: hr,
        hrtao_fraction_of_raw: div(hr, raw),
        hrtao_fraction_of_raw_pass: div(hr, raw_pass),
        hrtao_first_rays: hf.rays,
        rtao_first_rays: rf.rays,
    }
}

fn err_point(rays_per_pixel: f64, e: AoError) -> CurvePoint {
    CurvePoint {
        rays_per_pixel,
        mae: e.mae,
        rmse: e.rmse,
    }
}

/// Frame counts of the progressive run at which the RTAO error is measured: 1, 2, 3, 4, 6, 8, 12, ... up to `max`.
pub fn checkpoints(max: u32) -> Vec<u32> {
    let mut out = Vec::new();
    let mut p = 1u32;
    while p <= max {
        out.push(p);
        let mid = p + p / 2;
        if p >= 2 && mid <= max {
            out.push(mid);
        }
        p = p.saturating_mul(2);
    }
    if out.last() != Some(&max) && max > 0 {
        out.push(max);
    }
    out.sort_unstable();
    out.dedup();
    out
}

fn measure_quality(
    args: &BenchArgs,
    r: &mut Renderer,
    scene_gpu: &SceneGpu,
    sf: u32,
    camera: &Camera,
    hrtao_settings: &AoSettings,
) -> Result<Quality> {
    let b = hrtao_settings.map.rays_per_pixel;
    let step = args.step;
    let max_rays = if args.max_rays == 0 {
        (64 * b).max(64)
    } else {
        args.max_rays
    };
    let search_frames = max_rays.div_ceil(step).max(1);
    let ref_frames = args.ref_rays.div_ceil(step).max(2);
    let total_frames = search_frames + ref_frames;
    let marks = checkpoints(search_frames);
    let half = search_frames + ref_frames / 2;

    // Progressive per-pixel RTAO, `step` rays per frame, one accumulation.
    let progressive = {
        let mut s = hrtao_settings.clone();
        s.display.mode = Mode::Rtao;
        s.map.rays_per_pixel = step;
        s
    };
    r.restart_still_image();
    log::info!(
        "quality: progressive per-pixel RTAO, {total_frames} frames of {step} rays (search up to {} rays, reference {} rays)",
        search_frames * step,
        ref_frames * step
    );
    let mut avgs: BTreeMap<u32, Vec<f32>> = BTreeMap::new();
    let mut covered = 0u64;
    for f in 1..=total_frames {
        let rep = r.render(&FrameDesc::new(scene_gpu, sf, *camera, &progressive))?;
        if rep.accumulated_frames != f {
            bail!(
                "per-pixel RTAO accumulation restarted at frame {f} (accumulated {})",
                rep.accumulated_frames
            );
        }
        if f == 1 {
            covered = rep.rays / step as u64;
        }
        if marks.contains(&f) || f == half || f == total_frames {
            avgs.insert(f, r.read_ao()?);
        }
    }
    let n = |frames: u32| frames as u64 * step as u64;
    let reference = segment_mean(
        &avgs[&search_frames],
        n(search_frames),
        &avgs[&total_frames],
        n(total_frames),
    );
    let ref_a = segment_mean(&avgs[&search_frames], n(search_frames), &avgs[&half], n(half));
    let ref_b = segment_mean(&avgs[&half], n(half), &avgs[&total_frames], n(total_frames));
    let ref_noise_mae = ao_error(&ref_a, &ref_b).mae / 2.0;
    let rtao_curve: Vec<CurvePoint> = marks
        .iter()
        .map(|&f| err_point(n(f) as f64, ao_error(&avgs[&f], &reference)))
        .collect();
    drop(avgs);

    // Per-pixel RTAO, one frame at B (samples 0..B, disjoint from the reference when B <= max_rays).
    let rtao_b = {
        let mut s = hrtao_settings.clone();
        s.display.mode = Mode::Rtao;
        s
    };
    r.restart_still_image();
    r.render(&FrameDesc::new(scene_gpu, sf, *camera, &rtao_b))?;
    let rtao_b_img = r.read_ao()?;
    let rtao_same_b = err_point(b as f64, ao_error(&rtao_b_img, &reference));

    // HRTAO from an empty map, static camera: ours, and the paper's behaviour.
    let mae_curve: Vec<(f64, f64)> = rtao_curve.iter().map(|p| (p.rays_per_pixel, p.mae)).collect();
    let rmse_curve: Vec<(f64, f64)> = rtao_curve.iter().map(|p| (p.rays_per_pixel, p.rmse)).collect();
    let curves = (&mae_curve[..], &rmse_curve[..]);
    let frames = args.hrtao_frames.max(1);
    let ours = still_run(
        r,
        scene_gpu,
        sf,
        camera,
        hrtao_settings,
        frames,
        covered,
        &reference,
        curves,
    )?;
    let paper = still_run(
        r,
        scene_gpu,
        sf,
        camera,
        &hrtao_settings.paper(),
        frames,
        covered,
        &reference,
        curves,
    )?;
    let hrtao_curve = ours.curve;
    let (hrtao_first_img, hrtao_last_img) = (ours.first_img, ours.last_img);
    let first = &hrtao_curve[0];
    let match_mae = rays_to_reach(&mae_curve, first.mae);
    let match_rmse = rays_to_reach(&rmse_curve, first.rmse);
    let ratio = |m: &Match| m.rays_per_pixel / first.rays_per_pixel.max(1e-9);

    let external = match &args.reference {
        None => None,
        Some(p) => {
            let (ew, eh, ext) = imageio::read_ao(p)?;
            let (w, h) = r.size();
            if (ew, eh) != (w, h) {
                bail!(
                    "--reference {} is {ew}x{eh}, the bench renders {w}x{h}",
                    p.display()
                );
            }
            Some(ExternalErrors {
                path: p.display().to_string(),
                reference_vs_external: ao_error(&reference, &ext).into(),
                rtao_same_b: ao_error(&rtao_b_img, &ext).into(),
                hrtao_first: ao_error(&hrtao_first_img, &ext).into(),
                hrtao_last: ao_error(&hrtao_last_img, &ext).into(),
            })
        }
    };
    Ok(Quality {
        covered_pixels: covered,
        step,
        max_rays: search_frames * step,
        ref_rays: ref_frames * step,
        ref_noise_mae,
        rays_ratio_mae: ratio(&match_mae),
        rays_ratio_rmse: ratio(&match_rmse),
        match_mae,
        match_rmse,
        rtao_curve,
        rtao_same_b,
        hrtao_curve,
        hrtao_flicker: ours.flicker,
        paper_curve: paper.curve,
        paper_flicker: paper.flicker,
        external,
    })
}

/// An error curve: (rays per pixel, error) points.
type Curve<'a> = &'a [(f64, f64)];

/// One still-camera HRTAO run from an empty map.
struct StillRun {
    curve: Vec<HrtaoPoint>,
    /// Mean |ΔAO| between consecutive frames after frame 4 (None: too few frames).
    flicker: Option<f64>,
    first_img: Vec<f32>,
    last_img: Vec<f32>,
}

/// Mean |a - b| over all pixels.
pub fn mean_abs_diff(a: &[f32], b: &[f32]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64).sum::<f64>() / a.len().max(1) as f64
}

/// HRTAO from an empty map for `frames` still frames: its error curve against `reference` (beside per-pixel
/// RTAO at the same cumulated rays, from `curves` = (MAE, RMSE) curves) and its flicker.
#[allow(clippy::too_many_arguments)]
fn still_run(
    r: &mut Renderer,
    scene_gpu: &SceneGpu,
    sf: u32,
    camera: &Camera,
    settings: &AoSettings,
    frames: u32,
    covered: u64,
    reference: &[f32],
    (mae_curve, rmse_curve): (Curve, Curve),
) -> Result<StillRun> {
    r.restart_still_image();
    r.clear_cache()?;
    let mut curve = Vec::new();
    let mut cum_rays = 0u64;
    let mut first_img = Vec::new();
    let mut prev: Vec<f32> = Vec::new();
    let (mut flicker, mut flicker_n) = (0.0, 0u32);
    for f in 1..=frames {
        let rep = r.render(&FrameDesc::new(scene_gpu, sf, *camera, settings))?;
        cum_rays += rep.rays;
        let img = r.read_ao()?;
        let e = ao_error(&img, reference);
        let rpp = cum_rays as f64 / covered.max(1) as f64;
        curve.push(HrtaoPoint {
            frame: f as usize,
            rays_per_pixel: rpp,
            mae: e.mae,
            rmse: e.rmse,
            rtao_mae_same_rays: stats::error_at(mae_curve, rpp),
            rtao_rmse_same_rays: stats::error_at(rmse_curve, rpp),
        });
        if f == 1 {
            first_img = img.clone();
        }
        if f >= 5 {
            flicker += mean_abs_diff(&img, &prev);
            flicker_n += 1;
        }
        prev = img;
    }
    Ok(StillRun {
        curve,
        flicker: (flicker_n > 0).then(|| flicker / flicker_n as f64),
        first_img,
        last_img: prev,
    })
}

fn print_summary(r: &BenchResult) {
    let s = &r.summary;
    println!(
        "{} ({}x{}, B = {}): {} instances, {} instanced triangles",
        r.scene.label,
        r.width,
        r.height,
        r.settings["rays_per_pixel"],
        r.scene.instances,
        r.scene.instanced_triangles
    );
    println!(
        "  Table 1 (HRTAO passes, GPU ms): first {:.2}, nav {:.2}, nav/first {:.3} (whole frames {:.2} / {:.2} = {:.3})",
        s.first_ms, s.nav_ms, s.nav_over_first, s.first_frame_gpu_ms, s.nav_frame_gpu_ms, s.nav_over_first_frame
    );
    println!(
        "  Table 2 (first frame, GPU ms): cell finder {:.2}, ray-tracing update {:.2}, per-pixel AO {:.2}, filtering {:.2}; non-ray share {:.1}%",
        s.cell_finder_ms,
        s.ray_tracing_update_ms,
        s.per_pixel_ao_ms,
        s.filtering_ms,
        s.non_ray_share * 100.0
    );
    println!(
        "  throughput (rays/ms): raw {:.0} (AO pass alone {:.0}), HRTAO ray pass {:.0} = {:.1}% of raw ({:.1}% of the AO pass)",
        s.raw_rays_per_ms,
        s.raw_pass_rays_per_ms,
        s.hrtao_rays_per_ms,
        s.hrtao_fraction_of_raw * 100.0,
        s.hrtao_fraction_of_raw_pass * 100.0
    );
    if let Some(q) = &r.quality {
        let h = &q.hrtao_curve[0];
        println!(
            "  error vs per-pixel RTAO reference ({} rays, noise {:.4}): HRTAO 1 frame MAE {:.4} at {:.1} rays/px; RTAO at B MAE {:.4}; RTAO needs {:.0} rays/px ({:?}) = {:.1}x",
            q.ref_rays, q.ref_noise_mae, h.mae, h.rays_per_pixel, q.rtao_same_b.mae, q.match_mae.rays_per_pixel, q.match_mae.kind, q.rays_ratio_mae
        );
    }
    println!(
        "  load {:.0} ms, host peak {:.0} MiB, device {:.0} MiB, bench {:.0} s",
        r.scene.load_ms,
        r.memory.host_peak_bytes as f64 / 1048576.0,
        r.memory.device_total_bytes as f64 / 1048576.0,
        r.total_bench_s
    );
}
