//! The bench's pure maths: disjoint reference segments from progressive averages, error-curve interpolation,
//! orbit cameras, dates (medians and slopes: `hrtao_core::stats`). No GPU here (unit-tested in
//! `tests/bench_math.rs`).
use hrtao_core::bench_json::{Match, MatchKind};
use hrtao_core::stats::fit_slope;

/// Mean over samples `n_a..n_b` of a sequence, given the running means `avg_a` of its first `n_a` samples and
/// `avg_b` of its first `n_b` samples (per pixel). This turns one progressive per-pixel RTAO run into estimates
/// over disjoint sample ranges, so the reference shares no sample with the estimates it judges.
pub fn segment_mean(avg_a: &[f32], n_a: u64, avg_b: &[f32], n_b: u64) -> Vec<f32> {
    assert!(n_b > n_a, "segment_mean needs n_b > n_a");
    assert_eq!(avg_a.len(), avg_b.len());
    let (na, nb) = (n_a as f64, n_b as f64);
    avg_a
        .iter()
        .zip(avg_b)
        .map(|(&a, &b)| {
            let m = (nb * b as f64 - na * a as f64) / (nb - na);
            m.clamp(0.0, 1.0) as f32
        })
        .collect()
}

/// Rays per pixel at which a decreasing error curve `(rays, err)` reaches `target`: the first crossing,
/// interpolated linearly in log(rays)-log(err); beyond the ends, the power law of the end segments (the tail fits
/// its last half) extrapolates. Points with non-positive rays or error are ignored.
pub fn rays_to_reach(curve: &[(f64, f64)], target: f64) -> Match {
    let pts: Vec<(f64, f64)> = curve
        .iter()
        .copied()
        .filter(|(n, e)| *n > 0.0 && *e > 0.0 && n.is_finite() && e.is_finite())
        .map(|(n, e)| (n.ln(), e.ln()))
        .collect();
    let unknown = Match {
        rays_per_pixel: f64::NAN,
        kind: MatchKind::Unknown,
    };
    if pts.len() < 2 || target.is_nan() || target <= 0.0 || !target.is_finite() {
        return unknown;
    }
    let t = target.ln();
    if t >= pts[0].1 {
        let slope = fit_slope(&pts[..2]);
        let n = if slope < 0.0 {
            pts[0].0 + (t - pts[0].1) / slope
        } else {
            pts[0].0
        };
        return Match {
            rays_per_pixel: n.min(pts[0].0).exp(),
            kind: MatchKind::BelowFirst,
        };
    }
    for w in pts.windows(2) {
        let ((n0, e0), (n1, e1)) = (w[0], w[1]);
        if e1 <= t && t <= e0 {
            let f = if e0 == e1 { 0.0 } else { (e0 - t) / (e0 - e1) };
            return Match {
                rays_per_pixel: (n0 + f * (n1 - n0)).exp(),
                kind: MatchKind::Interpolated,
            };
        }
    }
    let tail = &pts[pts.len() / 2..];
    let tail = if tail.len() < 2 {
        &pts[pts.len() - 2..]
    } else {
        tail
    };
    let slope = fit_slope(tail);
    let (nl, el) = *pts.last().unwrap();
    if slope >= 0.0 {
        return Match {
            rays_per_pixel: f64::INFINITY,
            kind: MatchKind::BeyondLast,
        };
    }
    Match {
        rays_per_pixel: (nl + (t - el) / slope).max(nl).exp(),
        kind: MatchKind::BeyondLast,
    }
}

/// Rays within this fraction past either end of a curve take that end's error: HRTAO's adaptive sampling rounds
/// its rays stochastically, so a run meant to match the curve's last point can land a few rays beyond it.
pub const CURVE_END_SLACK: f64 = 0.02;

/// The error of a curve at `rays` (log-log interpolation within the measured range, its ends' errors within
/// `CURVE_END_SLACK` past them; NaN further out).
pub fn error_at(curve: &[(f64, f64)], rays: f64) -> f64 {
    let pts: Vec<(f64, f64)> = curve
        .iter()
        .copied()
        .filter(|(n, e)| *n > 0.0 && *e > 0.0)
        .collect();
    if pts.is_empty() || rays.is_nan() || rays <= 0.0 {
        return f64::NAN;
    }
    for w in pts.windows(2) {
        let ((n0, e0), (n1, e1)) = (w[0], w[1]);
        if n0 <= rays && rays <= n1 {
            let f = if n1 == n0 {
                0.0
            } else {
                (rays.ln() - n0.ln()) / (n1.ln() - n0.ln())
            };
            return (e0.ln() + f * (e1.ln() - e0.ln())).exp();
        }
    }
    let (first, last) = (pts[0], pts[pts.len() - 1]);
    if rays <= first.0 && rays * (1.0 + CURVE_END_SLACK) >= first.0 {
        return first.1;
    }
    if rays >= last.0 && rays <= last.0 * (1.0 + CURVE_END_SLACK) {
        return last.1;
    }
    f64::NAN
}

/// Rotates `eye` about the axis through `target` along `up` by `deg` degrees (right-handed).
pub fn orbit_eye(eye: [f32; 3], target: [f32; 3], up: [f32; 3], deg: f32) -> [f32; 3] {
    let axis = glam::Vec3::from(up).normalize_or_zero();
    if axis == glam::Vec3::ZERO {
        return eye;
    }
    let q = glam::Quat::from_axis_angle(axis, deg.to_radians());
    let t = glam::Vec3::from(target);
    (t + q * (glam::Vec3::from(eye) - t)).to_array()
}

/// `YYYY-MM-DD HH:MM UTC` for seconds since the Unix epoch.
pub fn utc_date(unix_secs: u64) -> String {
    i64::try_from(unix_secs)
        .ok()
        .and_then(|s| jiff::Timestamp::from_second(s).ok())
        .unwrap_or(jiff::Timestamp::MAX)
        .strftime("%Y-%m-%d %H:%M UTC")
        .to_string()
}
