//! Summary statistics of measured samples (frame times, ratios, error curves), shared by the bench, the viewer's
//! `--stats` log, the report of `docs/benchmarks.md` and the examples.

/// Median of the finite values (NaN when there are none).
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Median of the per-frame ratios `a[i] / b[i]` of two runs over the same frames, interleaved (NaN when no
/// pair has a positive `b`). A change of load on the machine hits both frames of a pair alike, so this is the
/// cost ratio that noise moves least; the ratio of the two medians pairs unrelated frames.
pub fn paired_ratio(a: &[f64], b: &[f64]) -> f64 {
    let ratios: Vec<f64> = a
        .iter()
        .zip(b)
        .filter(|(_, &y)| y > 0.0)
        .map(|(x, y)| x / y)
        .collect();
    median(&ratios)
}

/// Least-squares slope of y over x (NaN with fewer than two points or a single x).
pub fn fit_slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return f64::NAN;
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    if sxx == 0.0 {
        f64::NAN
    } else {
        sxy / sxx
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_nan() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&[f64::NAN, 5.0]), 5.0);
        assert_eq!(median(&[f64::INFINITY, 1.0, 3.0]), 2.0);
        assert!(median(&[]).is_nan());
        assert!(median(&[f64::NAN]).is_nan());
    }

    #[test]
    fn paired_ratio_is_the_median_of_frame_by_frame_ratios() {
        // The load triples the cost of the second pair (both frames of it) and the third pair is a noisy one: the
        // pairs say 0.9, the medians of the two runs, taken over unrelated frames, say 0.95.
        let ours = [90.0, 270.0, 95.0];
        let paper = [100.0, 300.0, 90.0];
        assert!((paired_ratio(&ours, &paper) - 0.9).abs() < 1e-12);
        assert!((median(&ours) / median(&paper) - 0.95).abs() < 1e-12);
        // Pairs without a positive base are skipped; none at all gives NaN.
        assert!((paired_ratio(&[1.0, 5.0], &[0.0, 10.0]) - 0.5).abs() < 1e-12);
        assert!(paired_ratio(&[1.0], &[0.0]).is_nan());
    }

    #[test]
    fn fit_slope_of_a_line() {
        let pts = [(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)];
        assert!((fit_slope(&pts) - 2.0).abs() < 1e-12);
        assert!(fit_slope(&pts[..1]).is_nan());
        assert!(fit_slope(&[(1.0, 1.0), (1.0, 2.0)]).is_nan());
    }
}
