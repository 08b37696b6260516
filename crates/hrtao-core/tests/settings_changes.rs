//! Settings changed mid-run give, after the frames their class needs (`AoSettings::invalidates`), the image a
//! fresh renderer gives with those settings: no cell keeps AO gathered under the old meaning of a setting.
//! On the bundled scene (assets/default.glb and its camera), at 160 x 90, with refinement off so cells show.
mod common;

use common::*;
use std::sync::Arc;

use hrtao_core::{AoSettings, Camera, Gpu, Invalidates, SceneGpu};

/// The AO radius used with the bundled scene (assets/README.md).
const R: f32 = 8.0;

/// The defaults at R with refinement off (cells show) and a table sized for 160 x 90.
fn base() -> AoSettings {
    let mut s = hrtao(4, R);
    s.still.refine = false;
    s.map.hash_capacity = 1 << 17;
    s
}

/// Mean |a - b| over the pixels where either is not open.
fn mae_px(a: &[f32], b: &[f32]) -> f32 {
    mae(a, b)
}

/// `frames` frames of a fresh renderer with `s`; `warmup` frames without AO first (another frame index) and
/// keys of scene F `f` (another QMC scrambling): a render with independent noise.
fn fresh(
    gpu: &Arc<Gpu>,
    sg: &SceneGpu,
    cam: &Camera,
    s: &AoSettings,
    frames: u32,
    warmup: u32,
    f: u32,
) -> Vec<f32> {
    let mut r = Headless::new(gpu, cam.width, cam.height, s.clone()).unwrap();
    if warmup > 0 {
        r.set_settings({
            let mut s = s.clone();
            s.display.mode = hrtao_core::Mode::NoAo;
            s
        })
        .unwrap();
        for _ in 0..warmup {
            r.render(sg, f, cam).unwrap();
        }
        r.set_settings(s.clone()).unwrap();
    }
    for _ in 0..frames {
        r.render(sg, f, cam).unwrap();
    }
    r.read_ao().unwrap()
}

/// What one change did: its class; the frame after it (accumulated frames, key F before and after); and for
/// a change of the whole map, the image `after` frames later against a fresh renderer's with the new settings
/// (MAE, mean difference) and the same between two fresh renders of other frame indices and keys (the floor).
struct Changed {
    class: Invalidates,
    accumulated: u32,
    f_before: u32,
    f_after: u32,
    error: f32,
    floor: f32,
    bias: f32,
    floor_bias: f32,
}

fn mean(a: &[f32]) -> f32 {
    a.iter().sum::<f32>() / a.len() as f32
}

fn change(
    gpu: &Arc<Gpu>,
    sg: &SceneGpu,
    cam: &Camera,
    from: &AoSettings,
    to: &AoSettings,
    before: u32,
    after: u32,
) -> Changed {
    let mut r = Headless::new(gpu, cam.width, cam.height, from.clone()).unwrap();
    let mut f_before = 0;
    for _ in 0..before {
        f_before = r.render(sg, 0, cam).unwrap().map_f;
    }
    r.set_settings(to.clone()).unwrap();
    let first = r.render(sg, 0, cam).unwrap();
    let class = from.invalidates(to);
    let mut c = Changed {
        class,
        accumulated: first.accumulated_frames,
        f_before,
        f_after: first.map_f,
        error: 0.0,
        floor: 0.0,
        bias: 0.0,
        floor_bias: 0.0,
    };
    if class == Invalidates::WholeMap {
        for _ in 1..after {
            r.render(sg, 0, cam).unwrap();
        }
        let continued = r.read_ao().unwrap();
        let a = fresh(gpu, sg, cam, to, after, 0, 0);
        let b = fresh(gpu, sg, cam, to, after, 3, 7);
        c.error = mae_px(&continued, &a);
        c.floor = mae_px(&a, &b);
        c.bias = mean(&continued) - mean(&a);
        c.floor_bias = mean(&b) - mean(&a);
    }
    c
}

/// A changed value for every setting that is not a switch (the test fails on a setting missing here); a
/// switch (every addition of ours) is changed by flipping it, so an addition comes and goes without an edit here.
fn changed_values() -> Vec<(&'static str, serde_json::Value)> {
    use serde_json::json;
    vec![
        ("mode", json!("rtao")),
        ("ao_radius", json!(1.5 * R)),
        ("rays_per_pixel", json!(8)),
        ("s_p", json!(8.0)),
        ("s_nd", json!(5.0)),
        ("s_min", json!(0.5)),
        ("max_samples", json!(200)),
        ("min_samples", json!(0)),
        ("hash_capacity", json!(1 << 18)),
        ("cache_lifetime_s", json!(5.0)),
        ("filter_iterations", json!(2)),
        ("still_samples", json!(16)),
        ("crease_deg", json!(20.0)),
        ("environment", json!("uniform")),
        ("environment_rotation", json!(45.0)),
        ("environment_intensity", json!(2.0)),
        ("sky_up", json!("Z")),
    ]
}

/// Every setting the panel offers, and the Defaults and Paper presets, changed after 8 frames. The frame after
/// the change restarts the still image unless the class is "nothing", and keys cells with a new F exactly when
/// the class is "whole map"; a "whole map" change ends 8 frames later at a fresh renderer's 8 frames, within
/// MAE max(0.005, 1.5 x the floor between two fresh renders) and a mean difference within max(0.004, 3 x that
/// floor's). Catches: a setting that changes what a cell holds (AO radius, s_nd,
/// near fraction, ...) classified below "whole map" (the cells keep the old AO, as `set_settings` did before),
/// and any setting classified above what it invalidates (the map would be emptied for nothing).
#[test]
fn every_setting_changed_mid_run_gives_a_fresh_renderers_image() {
    let (gpu, _scene, cam, sg) = on_gpu(bundled(160, 90));
    let base = base();
    let fields = serde_json::to_value(&base).unwrap();
    let mut values: Vec<(String, serde_json::Value)> = changed_values()
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    for (key, value) in fields.as_object().unwrap() {
        if let Some(on) = value.as_bool() {
            values.push((key.clone(), serde_json::json!(!on)));
        }
        assert!(
            values.iter().any(|(k, _)| k == key),
            "no changed value for setting {key}: add it to changed_values()"
        );
    }
    let mut cases: Vec<(String, AoSettings, AoSettings)> = values
        .iter()
        .map(|(k, v)| {
            let to = base
                .with_overrides(&serde_json::json!({ k.as_str(): v }).to_string())
                .unwrap();
            (k.clone(), base.clone(), to)
        })
        .collect();
    // The presets: Paper from our defaults, Defaults from a session that changed the radius and s_nd.
    cases.push(("Paper preset".into(), base.clone(), base.paper()));
    let edited = base
        .with_overrides(r#"{"ao_radius": 12.0, "s_nd": 5.0}"#)
        .unwrap();
    let defaults = {
        let mut s = AoSettings::default();
        s.map.ao_radius = R;
        s.still.refine = false;
        s.map.hash_capacity = 1 << 17;
        s
    };
    cases.push(("Defaults preset".into(), edited, defaults));
    let mut failures = Vec::new();
    for (name, from, to) in cases {
        let c = change(&gpu, &sg, &cam, &from, &to, 8, 8);
        let bound = (1.5 * c.floor).max(0.005);
        let bias_bound = (3.0 * c.floor_bias.abs()).max(0.004);
        eprintln!(
            "{name:>18}: {:?}, accumulated {}, F {} -> {}; MAE {:.4} vs fresh (floor {:.4}, bound {bound:.4}), \
             mean difference {:+.4} (floor {:+.4}, bound {bias_bound:.4})",
            c.class, c.accumulated, c.f_before, c.f_after, c.error, c.floor, c.bias, c.floor_bias
        );
        let restarted = c.accumulated == 1;
        let rekeyed = c.f_after != c.f_before;
        if c.error > bound || c.bias.abs() > bias_bound {
            failures.push(format!(
                "{name}: MAE {:.4} (bound {bound:.4}), mean difference {:+.4} (bound {bias_bound:.4}) against a fresh renderer",
                c.error, c.bias
            ));
        }
        if restarted != (c.class >= Invalidates::StillImage) {
            failures.push(format!(
                "{name}: {:?} but the still image restarted: {restarted}",
                c.class
            ));
        }
        if rekeyed != (c.class == Invalidates::WholeMap) {
            failures.push(format!(
                "{name}: {:?} but the cells were re-keyed: {rekeyed}",
                c.class
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    assert_clean(&gpu);
}

/// The radius case: 32 frames at R then 32 at 1.5 R end within MAE max(0.005, 1.5 x the floor between two
/// fresh renders whose frame indices differ) of a fresh 32 frames at 1.5 R, refinement off. Before the fix the
/// cells kept the AO gathered at R (`set_settings` re-keyed nothing).
#[test]
fn a_radius_change_mid_run_ends_at_a_fresh_renders_image() {
    let (gpu, _scene, cam, sg) = on_gpu(bundled(160, 90));
    let from = base();
    let to = {
        let mut s = from.clone();
        s.map.ao_radius = 1.5 * R;
        s
    };
    let c = change(&gpu, &sg, &cam, &from, &to, 32, 32);
    assert_eq!(c.class, Invalidates::WholeMap);
    let bound = (1.5 * c.floor).max(0.005);
    let (at_r, at_15r) = (
        fresh(&gpu, &sg, &cam, &from, 32, 0, 0),
        fresh(&gpu, &sg, &cam, &to, 32, 0, 0),
    );
    eprintln!(
        "R {R} -> {}: MAE {:.4} against fresh (floor {:.4}, bound {bound:.4}); R vs 1.5 R fresh: {:.4}",
        1.5 * R,
        c.error,
        c.floor,
        mae_px(&at_r, &at_15r)
    );
    assert!(c.error <= bound, "MAE {:.4} > {bound:.4}", c.error);
    assert_clean(&gpu);
}
