//! Small PNG line plots with the `image` crate (no fonts needed: tick labels use a built-in 3×5 digit font;
//! axis titles and legends live in the markdown beside the image).
use std::path::Path;

use anyhow::{Context, Result};
use image::{Rgb, RgbImage};

pub const COLORS: [[u8; 3]; 6] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [127, 127, 127],
];

pub struct Series {
    pub points: Vec<(f64, f64)>,
    pub color: [u8; 3],
    pub dashed: bool,
    pub markers: bool,
}

pub struct Plot {
    pub width: u32,
    pub height: u32,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
}

const MARGIN_L: i32 = 56;
const MARGIN_B: i32 = 30;
const MARGIN_T: i32 = 12;
const MARGIN_R: i32 = 16;

/// The digits' 3×5 glyphs, 15 bits each: an octal digit per row, the top row first (bit 2 of a row = left).
const DIGITS: [u16; 10] = [
    0o75557, 0o26227, 0o71747, 0o71717, 0o55711, 0o74717, 0o74757, 0o71111, 0o75757, 0o75717,
];

/// 3×5 glyphs, rows top first, 3 bits per row (MSB = left).
fn glyph(c: char) -> Option<[u8; 5]> {
    let bits = match c {
        '0'..='9' => DIGITS[c as usize - '0' as usize],
        '.' => 0o00002,
        '-' => 0o00700,
        'e' => 0o07747,
        _ => return None,
    };
    Some(std::array::from_fn(|row| ((bits >> (3 * (4 - row))) & 7) as u8))
}

struct Canvas {
    img: RgbImage,
}

impl Canvas {
    fn put(&mut self, x: i32, y: i32, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u32) < self.img.width() && (y as u32) < self.img.height() {
            self.img.put_pixel(x as u32, y as u32, Rgb(c));
        }
    }

    fn dot(&mut self, x: i32, y: i32, r: i32, c: [u8; 3]) {
        for dy in -r..=r {
            for dx in -r..=r {
                if dx * dx + dy * dy <= r * r + r / 2 {
                    self.put(x + dx, y + dy, c);
                }
            }
        }
    }

    /// A line of thickness ~2 px; `dash` > 0 draws `dash` px on, `dash` px off.
    fn line(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), c: [u8; 3], dash: u32) {
        let len = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
        let steps = (len.ceil() as u32).max(1) * 2;
        for i in 0..=steps {
            let t = i as f64 / steps as f64;
            if dash > 0 && ((t * len) as u32 / dash) % 2 == 1 {
                continue;
            }
            let (x, y) = (x0 + t * (x1 - x0), y0 + t * (y1 - y0));
            self.dot(x.round() as i32, y.round() as i32, 1, c);
        }
    }

    fn text(&mut self, x: i32, y: i32, s: &str, scale: i32, c: [u8; 3]) {
        let mut cx = x;
        for ch in s.chars() {
            if let Some(g) = glyph(ch) {
                for (row, bits) in g.iter().enumerate() {
                    for col in 0..3 {
                        if bits & (4 >> col) != 0 {
                            for sy in 0..scale {
                                for sx in 0..scale {
                                    self.put(cx + col * scale + sx, y + row as i32 * scale + sy, c);
                                }
                            }
                        }
                    }
                }
            }
            cx += 4 * scale;
        }
    }
}

fn text_width(s: &str, scale: i32) -> i32 {
    s.chars().count() as i32 * 4 * scale - scale
}

/// A compact tick label: 1e3 style for large/small magnitudes, else plain.
pub fn tick_label(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let e = a.log10().floor() as i32;
        let m = v / 10f64.powi(e);
        if (m - m.round()).abs() < 1e-6 && m.round().abs() == 1.0 {
            return format!("{}e{e}", if v < 0.0 { "-1" } else { "1" });
        }
        return format!("{m:.1}e{e}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// Tick positions: decades (and 2×, 5× when few decades) on log axes, 1-2-5 steps on linear ones.
pub fn ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    let mut out = Vec::new();
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return out;
    }
    if log {
        let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        let mults: &[f64] = if b - a <= 2 { &[1.0, 2.0, 5.0] } else { &[1.0] };
        for e in a..=b {
            for m in mults {
                let v = m * 10f64.powi(e);
                if v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9) {
                    out.push(v);
                }
            }
        }
    } else {
        let raw = (hi - lo) / 5.0;
        let mag = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * mag)
            .find(|s| *s >= raw)
            .unwrap_or(10.0 * mag);
        let mut v = (lo / step).ceil() * step;
        while v <= hi + 1e-9 * step {
            out.push(if v.abs() < 1e-12 * step { 0.0 } else { v });
            v += step;
        }
    }
    out
}

impl Plot {
    fn range(&self, log: bool, pick: impl Fn(&(f64, f64)) -> f64) -> (f64, f64) {
        let vals: Vec<f64> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(&pick))
            .filter(|v| v.is_finite() && (!log || *v > 0.0))
            .collect();
        let (mut lo, mut hi) = vals.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
        if !lo.is_finite() {
            return (1.0, 10.0);
        }
        if log {
            lo = 10f64.powf((lo.log10() * 10.0).floor() / 10.0);
            hi = 10f64.powf((hi.log10() * 10.0).ceil() / 10.0);
            if hi <= lo {
                hi = lo * 10.0;
            }
        } else {
            let pad = ((hi - lo) * 0.05).max(1e-9);
            lo = if lo >= 0.0 { 0.0 } else { lo - pad };
            hi += pad;
        }
        (lo, hi)
    }

    pub fn render(&self) -> RgbImage {
        let (w, h) = (self.width as i32, self.height as i32);
        let mut c = Canvas {
            img: RgbImage::from_pixel(self.width, self.height, Rgb([255, 255, 255])),
        };
        let (x_lo, x_hi) = self.range(self.log_x, |p| p.0);
        let (y_lo, y_hi) = self.range(self.log_y, |p| p.1);
        let (px0, px1) = (MARGIN_L as f64, (w - MARGIN_R) as f64);
        let (py0, py1) = ((h - MARGIN_B) as f64, MARGIN_T as f64);
        let map = |v: f64, lo: f64, hi: f64, log: bool, a: f64, b: f64| {
            let t = if log {
                (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
            } else {
                (v - lo) / (hi - lo)
            };
            a + t * (b - a)
        };
        let mx = |v: f64| map(v, x_lo, x_hi, self.log_x, px0, px1);
        let my = |v: f64| map(v, y_lo, y_hi, self.log_y, py0, py1);
        let grid = [225, 225, 225];
        let ink = [40, 40, 40];
        for t in ticks(x_lo, x_hi, self.log_x) {
            let x = mx(t);
            c.line((x, py0), (x, py1), grid, 0);
            let label = tick_label(t);
            c.text(
                x as i32 - text_width(&label, 2) / 2,
                h - MARGIN_B + 8,
                &label,
                2,
                ink,
            );
        }
        for t in ticks(y_lo, y_hi, self.log_y) {
            let y = my(t);
            c.line((px0, y), (px1, y), grid, 0);
            let label = tick_label(t);
            c.text(MARGIN_L - 6 - text_width(&label, 2), y as i32 - 5, &label, 2, ink);
        }
        c.line((px0, py0), (px1, py0), ink, 0);
        c.line((px0, py0), (px0, py1), ink, 0);
        for s in &self.series {
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(|(x, y)| {
                    x.is_finite() && y.is_finite() && (!self.log_x || *x > 0.0) && (!self.log_y || *y > 0.0)
                })
                .map(|(x, y)| (mx(*x), my(*y)))
                .collect();
            for w in pts.windows(2) {
                c.line(w[0], w[1], s.color, if s.dashed { 6 } else { 0 });
            }
            if s.markers || pts.len() == 1 {
                for p in &pts {
                    c.dot(p.0.round() as i32, p.1.round() as i32, 3, s.color);
                }
            }
        }
        c.img
    }

    pub fn save(&self, path: &Path) -> Result<()> {
        self.render()
            .save(path)
            .with_context(|| format!("cannot write {}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_unpack_top_row_first() {
        assert_eq!(glyph('0'), Some([7, 5, 5, 5, 7]));
        assert_eq!(glyph('4'), Some([5, 5, 7, 1, 1]));
        assert_eq!(glyph('9'), Some([7, 5, 7, 1, 7]));
        assert_eq!(glyph('e'), Some([0, 7, 7, 4, 7]));
        assert_eq!(glyph('.'), Some([0, 0, 0, 0, 2]));
        assert_eq!(glyph('x'), None);
    }

    #[test]
    fn ticks_labels_and_image() {
        assert_eq!(ticks(1.0, 1000.0, true), vec![1.0, 10.0, 100.0, 1000.0]);
        assert_eq!(ticks(0.0, 10.0, false), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(tick_label(1e9), "1e9");
        assert_eq!(tick_label(0.05), "0.05");
        assert_eq!(tick_label(100.0), "100");
        let p = Plot {
            width: 200,
            height: 120,
            log_x: true,
            log_y: true,
            series: vec![Series {
                points: vec![(1.0, 0.1), (10.0, 0.01), (f64::NAN, 1.0)],
                color: COLORS[0],
                dashed: false,
                markers: true,
            }],
        };
        let img = p.render();
        assert_eq!(img.dimensions(), (200, 120));
        assert!(img.pixels().any(|px| px.0 == COLORS[0]), "the series is drawn");
    }
}
