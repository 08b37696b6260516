//! `hrtao bench` end to end on a tiny run (64×36, 3 navigation frames, validation on): the JSON schema, the
//! self-consistency of its numbers (no timing assertion), and that the report's reader (`hrtao_core::bench_json`,
//! what `bench-report` loads) parses it.
mod cli;
/// The test data helpers of the scene crate's tests (`testdata/`), shared rather than copied.
#[path = "../../scene/tests/common/mod.rs"]
mod common;

use std::path::PathBuf;
use std::process::Command;

fn scene() -> String {
    common::test_scene("rod").display().to_string()
}

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hrtao-bench-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `hrtao ARGS`, asserted successful, compiling its pipelines afresh (no Mesa shader cache).
fn hrtao(args: &[&str]) -> std::process::Output {
    cli::hrtao_ok_with(args, &[("MESA_SHADER_CACHE_DISABLE", "true")])
}

fn num(v: &serde_json::Value, path: &str) -> f64 {
    let mut cur = v;
    for k in path.split('.') {
        cur = match k.parse::<usize>() {
            Ok(i) => &cur[i],
            Err(_) => &cur[k],
        };
    }
    cur.as_f64()
        .unwrap_or_else(|| panic!("{path} is not a number: {cur}"))
}

#[test]
fn tiny_bench_writes_the_schema_the_report_reads() {
    let dir = tmp_dir("schema");
    let json = dir.join("tiny.json");
    let scene = scene();
    let extra = ["--step", "4", "--label", "tiny", "--json", json.to_str().unwrap()];
    hrtao(&cli::tiny_bench(&scene, ("3", "2"), &extra));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["schema"], "hrtao-bench/1");
    for key in [
        "date", "host", "device", "scene", "build", "memory", "camera", "settings", "hrtao", "rtao",
        "summary", "quality",
    ] {
        assert!(!v[key].is_null(), "missing {key}");
    }
    assert_eq!(num(&v, "width"), 64.0);
    assert_eq!(num(&v, "height"), 36.0);
    assert_eq!(
        v["validation_messages"], 0,
        "validation messages in the bench run"
    );
    assert!(num(&v, "host.cpu_cores") >= 1.0);

    // Frames: one first frame per repetition, 3 navigation frames, each with GPU sections and rays.
    for mode in ["hrtao", "paper", "rtao"] {
        assert_eq!(v[mode]["first"].as_array().unwrap().len(), 1);
        let nav = v[mode]["nav"].as_array().unwrap();
        assert_eq!(nav.len(), 3);
        for f in nav.iter().chain(v[mode]["first"].as_array().unwrap()) {
            for k in [
                "wall_ms",
                "gpu_total_ms",
                "hrtao_passes_ms",
                "rays",
                "occupied_cells",
                "failed_inserts",
            ] {
                assert!(f[k].is_number(), "{mode} frame lacks {k}: {f}");
            }
            assert!(f["passes"].is_object());
        }
    }
    let first = &v["hrtao"]["first"][0];
    if v["device"]["timestamps"] == true {
        for s in [
            "cell finder",
            "ray-tracing update",
            "per-pixel AO",
            "filtering",
            "primary visibility",
        ] {
            assert!(
                first["passes"][s].is_number(),
                "HRTAO first frame lacks section {s}"
            );
        }
        assert!(v["rtao"]["first"][0]["passes"]["per-pixel RTAO"].is_number());
        let sum: f64 = ["cell finder", "ray-tracing update", "per-pixel AO", "filtering"]
            .iter()
            .map(|s| first["passes"][*s].as_f64().unwrap())
            .sum();
        assert!((sum - num(first, "hrtao_passes_ms")).abs() < 1e-6);
    }
    let rays = num(first, "rays");
    assert!(rays > 0.0, "the first frame traced no ray");
    // Rays: B per covered pixel (per-pixel RTAO exactly; HRTAO's adaptive sampling shares three quarters of the
    // budget with stochastic rounding, so its total is B per pixel in expectation, within a few rays).
    let covered = num(&v, "quality.covered_pixels");
    assert!(covered > 0.0 && covered <= 64.0 * 36.0);
    assert_eq!(num(&v["rtao"]["first"][0], "rays"), 4.0 * covered);
    assert!(
        rays <= 1.02 * 4.0 * covered,
        "HRTAO traced {rays} rays on {covered} covered pixels at B = 4"
    );

    let s = &v["summary"];
    for k in [
        "first_ms",
        "nav_ms",
        "nav_over_first",
        "non_ray_share",
        "raw_rays_per_ms",
        "hrtao_rays_per_ms",
        "hrtao_fraction_of_raw",
        "cell_finder_ms",
        "ray_tracing_update_ms",
        "per_pixel_ao_ms",
        "filtering_ms",
    ] {
        assert!(s[k].is_number() || s[k].is_null(), "summary.{k}: {}", s[k]);
    }
    let share = s["non_ray_share"].as_f64().unwrap_or(0.0);
    assert!((0.0..=1.0).contains(&share));

    // Quality: curves with increasing rays, errors in [0, 1], a match on the RTAO curve.
    let q = &v["quality"];
    let curve = q["rtao_curve"].as_array().unwrap();
    let xs: Vec<f64> = curve.iter().map(|p| num(p, "rays_per_pixel")).collect();
    assert_eq!(xs, vec![4.0, 8.0]);
    assert_eq!(num(q, "ref_rays"), 16.0);
    for p in curve.iter().chain(q["hrtao_curve"].as_array().unwrap()) {
        let (mae, rmse) = (num(p, "mae"), num(p, "rmse"));
        assert!((0.0..=1.0).contains(&mae) && mae <= rmse + 1e-12, "{p}");
    }
    assert_eq!(q["hrtao_curve"].as_array().unwrap().len(), 2);
    // The paper's behaviour in the same run: the same still frames; with refinement off its second frame
    // traces no rays of its own, so it has at most the rays ours has.
    let paper = q["paper_curve"].as_array().unwrap();
    assert_eq!(paper.len(), 2);
    assert!(num(&paper[1], "rays_per_pixel") <= num(&q["hrtao_curve"][1], "rays_per_pixel") + 1e-9);
    assert_eq!(v["settings"]["refine"], true, "the bench's HRTAO is ours");
    assert!(q["match_mae"]["kind"].is_string());
    assert!(num(&v, "memory.host_peak_bytes") > 0.0);
    assert!(num(&v, "memory.device_total_bytes") >= num(&v, "memory.device_scene_bytes"));

    // The report's reader takes the file as written: the run's label, frames and curves come back.
    let read: hrtao_core::bench_json::BenchResult = serde_json::from_value(v.clone()).unwrap();
    assert_eq!(read.schema, hrtao_core::bench_json::SCHEMA);
    assert_eq!(read.scene.label, "tiny");
    assert_eq!(read.hrtao.nav.len(), 3);
    assert_eq!(read.paper.as_ref().map(|p| p.nav.len()), Some(3));
    assert_eq!(read.quality.as_ref().unwrap().hrtao_curve.len(), 2);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bench_rejects_bad_arguments() {
    let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(["bench", "--scene", "gen:box", "--orbit", "2", "--path", "x.json"])
        .output()
        .unwrap();
    assert!(!out.status.success(), "--orbit and --path together must fail");
    // The report is `bench-report`'s: the user's binary takes no --report, and measures nothing without --scene.
    for args in [&["bench", "--report", "docs/bench"][..], &["bench"][..]] {
        let out = Command::new(env!("CARGO_BIN_EXE_hrtao"))
            .args(args)
            .output()
            .unwrap();
        assert!(!out.status.success(), "hrtao {args:?} succeeded");
    }
    let help = Command::new(env!("CARGO_BIN_EXE_hrtao"))
        .args(["bench", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("--scene"), "{help}");
    assert!(
        !help.contains("--report") && !help.contains("--markdown"),
        "{help}"
    );
}
