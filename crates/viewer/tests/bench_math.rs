//! The bench's reference / error / interpolation maths (pure code, no GPU; medians and slopes are tested in
//! `hrtao_core::stats`).
#![allow(dead_code)]

#[path = "../src/bench/stats.rs"]
mod stats;

use hrtao_core::bench_json::MatchKind;
use stats::*;

#[test]
fn segment_mean_recovers_the_disjoint_average() {
    // A per-pixel sequence of samples; running means after 4 and 10 samples.
    let samples = [[1.0f32, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0], [0.5; 10]];
    let avg = |n: usize| -> Vec<f32> {
        samples
            .iter()
            .map(|s| s[..n].iter().sum::<f32>() / n as f32)
            .collect()
    };
    let seg = segment_mean(&avg(4), 4, &avg(10), 10);
    let expect0 = samples[0][4..].iter().sum::<f32>() / 6.0;
    assert!((seg[0] - expect0).abs() < 1e-6, "{} vs {expect0}", seg[0]);
    assert!((seg[1] - 0.5).abs() < 1e-6);
}

#[test]
fn rays_to_reach_inverts_a_power_law() {
    // err = 0.4 N^-0.5 at N = 4, 8, ..., 256.
    let curve: Vec<(f64, f64)> = (2..=8)
        .map(|k| 2f64.powi(k))
        .map(|n| (n, 0.4 / n.sqrt()))
        .collect();
    let m = rays_to_reach(&curve, 0.4 / 100f64.sqrt());
    assert_eq!(m.kind, MatchKind::Interpolated);
    assert!((m.rays_per_pixel - 100.0).abs() < 1e-6, "{m:?}");
    // Exactly on a measured point.
    let m = rays_to_reach(&curve, 0.4 / 16f64.sqrt());
    assert!((m.rays_per_pixel - 16.0).abs() < 1e-6);
    // Beyond the last point: extrapolated along the tail slope.
    let m = rays_to_reach(&curve, 0.4 / 1024f64.sqrt());
    assert_eq!(m.kind, MatchKind::BeyondLast);
    assert!((m.rays_per_pixel - 1024.0).abs() < 1e-3, "{m:?}");
    // Above the first point's error: below the first measured rays.
    let m = rays_to_reach(&curve, 0.4);
    assert_eq!(m.kind, MatchKind::BelowFirst);
    assert!(m.rays_per_pixel <= 4.0 && (m.rays_per_pixel - 1.0).abs() < 1e-6);
    assert_eq!(rays_to_reach(&curve[..1], 0.1).kind, MatchKind::Unknown);
}

#[test]
fn rays_to_reach_takes_the_first_crossing_of_a_noisy_curve() {
    let curve = [(4.0, 0.1), (8.0, 0.05), (16.0, 0.06), (32.0, 0.03)];
    let m = rays_to_reach(&curve, 0.055);
    assert_eq!(m.kind, MatchKind::Interpolated);
    assert!(m.rays_per_pixel > 4.0 && m.rays_per_pixel < 8.0);
    // A flat tail never reaches a lower error.
    let flat = [(4.0, 0.1), (8.0, 0.1), (16.0, 0.1)];
    assert!(rays_to_reach(&flat, 0.01).rays_per_pixel.is_infinite());
}

#[test]
fn error_at_interpolates_log_log_and_refuses_to_extrapolate() {
    let curve = [(4.0, 0.2), (16.0, 0.1)];
    assert!((error_at(&curve, 8.0) - 0.2 / 2f64.sqrt()).abs() < 1e-9);
    assert!((error_at(&curve, 4.0) - 0.2).abs() < 1e-12);
    assert!(error_at(&curve, 2.0).is_nan());
    assert!(error_at(&curve, 32.0).is_nan());
    // A few rays past an end (stochastic rounding) take that end's error, not NaN.
    let last = curve.last().unwrap();
    assert_eq!(error_at(&curve, last.0 * 1.01), last.1);
    assert!(error_at(&curve, last.0 * 1.05).is_nan());
}

#[test]
fn orbit_keeps_distance_and_height() {
    let eye = [10.0, 0.0, 3.0];
    let e = orbit_eye(eye, [0.0; 3], [0.0, 0.0, 1.0], 90.0);
    assert!((e[0]).abs() < 1e-4 && (e[1] - 10.0).abs() < 1e-4 && (e[2] - 3.0).abs() < 1e-6);
    assert_eq!(orbit_eye(eye, [0.0; 3], [0.0; 3], 10.0), eye);
}

#[test]
fn utc_dates() {
    assert_eq!(utc_date(0), "1970-01-01 00:00 UTC");
    assert_eq!(utc_date(1_700_000_000), "2023-11-14 22:13 UTC");
    assert_eq!(utc_date(951_782_400), "2000-02-29 00:00 UTC");
}
