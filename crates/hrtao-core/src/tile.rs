//! Tiles of a larger image: a renderer can draw a window of a W×H image (an off-axis part of the same frustum),
//! so a large screenshot is rendered tile by tile, a slice of work at a time, and assembled on the CPU.
//!
//! The shaders' pinhole camera is linear in the pixel's NDC (`dir = w + ndc.x u - ndc.y v`, common.glsl), so a
//! tile is the same camera with `u`, `v` scaled to the tile's share of the image and `w` moved to its centre:
//! every tile pixel gets exactly the ray of the full image's pixel. The background gradient (linear in y) is
//! remapped the same way. An orthographic camera's rays are parallel (`origin = eye + ndc.x u - ndc.y v`):
//! there the tile moves the eye instead of `w`. Tiles are rendered with a margin that is cropped away, so that the filter and the
//! feature edges see the same neighbours as in the full image.
use glam::Vec3;

use crate::camera::CameraFrame;

/// A renderer's image as a window of a larger `full` image, starting at pixel `origin` (which may lie outside:
/// margins of border tiles extend beyond the image).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    pub full: (u32, u32),
    pub origin: (i32, i32),
}

impl Tile {
    /// The camera frame of this tile of `size` pixels, from the frame of the full image (of an orthographic
    /// camera when `orthographic`).
    pub fn frame(&self, full: &CameraFrame, size: (u32, u32), orthographic: bool) -> CameraFrame {
        let (sx, ox) = axis(self.full.0, self.origin.0, size.0);
        let (sy, oy) = axis(self.full.1, self.origin.1, size.1);
        let centre = full.u * ox - full.v * oy;
        CameraFrame {
            eye: if orthographic { full.eye + centre } else { full.eye },
            u: full.u * sx,
            v: full.v * sy,
            w: if orthographic { full.w } else { full.w + centre },
        }
    }

    /// A perspective tile's centre in the tile's own NDC units: the rasteriser projects with the full image's
    /// axis and moves the image by this offset (an off-axis frustum), as `frame` moves `w` for the rays.
    pub fn ndc_offset(&self, size: (u32, u32)) -> [f32; 2] {
        let (sx, ox) = axis(self.full.0, self.origin.0, size.0);
        let (sy, oy) = axis(self.full.1, self.origin.1, size.1);
        [ox / sx, oy / sy]
    }

    /// The background gradient's top and bottom colours over this tile's rows (the gradient is linear in y).
    pub fn gradient(&self, top: [f32; 3], bottom: [f32; 3], height: u32) -> ([f32; 3], [f32; 3]) {
        let at = |y: i32| {
            let t = y as f32 / self.full.1.max(1) as f32;
            Vec3::from(top).lerp(Vec3::from(bottom), t).to_array()
        };
        (at(self.origin.1), at(self.origin.1 + height as i32))
    }
}

/// Along one axis: the scale of the tile's NDC and the full-image NDC of its centre.
fn axis(full: u32, origin: i32, size: u32) -> (f32, f32) {
    let full = full.max(1) as f32;
    (
        size as f32 / full,
        (2.0 * origin as f32 + size as f32) / full - 1.0,
    )
}

/// Equal tiles covering a `full` image, each at most about `max_pixels` (margins included), row by row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TileGrid {
    pub full: (u32, u32),
    /// The part of each tile that is kept.
    pub inner: (u32, u32),
    /// Pixels rendered around `inner` and cropped.
    pub margin: u32,
    /// Top-left pixel of each tile's inner part.
    pub origins: Vec<(u32, u32)>,
}

impl TileGrid {
    pub fn new(width: u32, height: u32, max_pixels: u64, margin: u32) -> TileGrid {
        let (w, h) = (width.max(1), height.max(1));
        let pixels = w as u64 * h as u64;
        let n = pixels.div_ceil(max_pixels.max(1)).max(1) as f64;
        // Near-square tiles: nx / ny follows the image's aspect.
        let mut nx = ((n * w as f64 / h as f64).sqrt().round() as u32).clamp(1, w);
        let mut ny = ((n / nx as f64).ceil() as u32).clamp(1, h);
        let mut inner = (w.div_ceil(nx), h.div_ceil(ny));
        // The margins add to each tile: split further (the longer side) while a tile is above the budget.
        let fits = |i: (u32, u32)| (i.0 + 2 * margin) as u64 * (i.1 + 2 * margin) as u64 <= max_pixels;
        while !fits(inner) && (nx < w || ny < h) {
            if (inner.0 >= inner.1 && nx < w) || ny >= h {
                nx += 1;
            } else {
                ny += 1;
            }
            inner = (w.div_ceil(nx), h.div_ceil(ny));
        }
        let nx = w.div_ceil(inner.0);
        let ny = h.div_ceil(inner.1);
        let origins = (0..ny)
            .flat_map(|ty| (0..nx).map(move |tx| (tx * inner.0, ty * inner.1)))
            .collect();
        TileGrid {
            full: (w, h),
            inner,
            margin,
            origins,
        }
    }

    /// The renderer's image size: a tile with its margins.
    pub fn render_size(&self) -> (u32, u32) {
        (self.inner.0 + 2 * self.margin, self.inner.1 + 2 * self.margin)
    }

    pub fn len(&self) -> usize {
        self.origins.len()
    }

    pub fn is_empty(&self) -> bool {
        self.origins.is_empty()
    }

    /// Tile `i` as the renderer draws it (margins included).
    pub fn tile(&self, i: usize) -> Tile {
        let (x, y) = self.origins[i];
        let m = self.margin as i32;
        Tile {
            full: self.full,
            origin: (x as i32 - m, y as i32 - m),
        }
    }

    /// Copies tile `i`'s inner pixels (4 bytes each) from the renderer's image into the full image.
    pub fn copy_inner(&self, i: usize, tile_px: &[u8], image: &mut [u8]) {
        let (x0, y0) = self.origins[i];
        let (rw, _) = self.render_size();
        let m = self.margin as usize;
        let cols = self.inner.0.min(self.full.0 - x0) as usize;
        let rows = self.inner.1.min(self.full.1 - y0) as usize;
        for r in 0..rows {
            let src = ((r + m) * rw as usize + m) * 4;
            let dst = ((y0 as usize + r) * self.full.0 as usize + x0 as usize) * 4;
            image[dst..dst + cols * 4].copy_from_slice(&tile_px[src..src + cols * 4]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;

    /// The shaders' ray through pixel (x, y) of an image of `size` with this frame (common.glsl).
    fn ray(f: &CameraFrame, size: (u32, u32), x: f32, y: f32) -> Vec3 {
        let nx = (x + 0.5) / size.0 as f32 * 2.0 - 1.0;
        let ny = (y + 0.5) / size.1 as f32 * 2.0 - 1.0;
        (f.w + nx * f.u - ny * f.v).normalize()
    }

    #[test]
    fn a_tile_pixel_gets_the_full_image_ray() {
        let cam = Camera::perspective([1.0, 2.0, 3.0], [0.0; 3], [0.0, 0.0, 1.0], 50.0, (400, 300));
        let full = cam.frame();
        let tile = Tile {
            full: (400, 300),
            origin: (-8, 130),
        };
        let size = (120, 90);
        let f = tile.frame(&full, size, false);
        for (x, y) in [(0.0, 0.0), (119.0, 89.0), (60.5, 12.25), (7.0, 80.0)] {
            let a = ray(&f, size, x, y);
            let b = ray(&full, (400, 300), x - 8.0, y + 130.0);
            assert!((a - b).length() < 1e-5, "({x}, {y}): {a} vs {b}");
        }
        // The whole image as one tile is the camera itself.
        let same = Tile {
            full: (400, 300),
            origin: (0, 0),
        }
        .frame(&full, (400, 300), false);
        assert!((same.w - full.w).length() < 1e-6 && (same.u - full.u).length() < 1e-6);
        // Orthographic: a tile pixel's ray starts where the full image's does, in the same direction.
        let ortho = cam.with_projection(crate::camera::Projection::Orthographic);
        let full = ortho.frame();
        let f = tile.frame(&full, size, true);
        let origin = |f: &CameraFrame, size: (u32, u32), x: f32, y: f32| {
            let nx = (x + 0.5) / size.0 as f32 * 2.0 - 1.0;
            let ny = (y + 0.5) / size.1 as f32 * 2.0 - 1.0;
            f.eye + nx * f.u - ny * f.v
        };
        for (x, y) in [(0.0, 0.0), (119.0, 89.0), (60.5, 12.25)] {
            let (a, b) = (
                origin(&f, size, x, y),
                origin(&full, (400, 300), x - 8.0, y + 130.0),
            );
            assert!((a - b).length() < 1e-4, "({x}, {y}): {a} vs {b}");
            assert!((f.w - full.w).length() < 1e-6);
        }
    }

    #[test]
    fn the_gradient_follows_the_rows() {
        let tile = Tile {
            full: (10, 100),
            origin: (0, 25),
        };
        let (t, b) = tile.gradient([0.0; 3], [1.0; 3], 50);
        assert!((t[0] - 0.25).abs() < 1e-6 && (b[0] - 0.75).abs() < 1e-6);
    }

    #[test]
    fn tiles_cover_the_image_once_within_the_budget() {
        for (w, h, budget, margin) in [
            (3840, 2160, 800_000, 8),
            (1000, 7, 100, 2),
            (17, 1, 5, 0),
            (640, 360, 1 << 20, 4),
        ] {
            let g = TileGrid::new(w, h, budget, margin);
            let (rw, rh) = g.render_size();
            if budget >= 10_000 {
                assert!(
                    rw as u64 * rh as u64 <= budget,
                    "{w}x{h}: tile {rw}x{rh} over {budget}"
                );
            }
            // Paint each tile's inner part with its index + 1: every pixel exactly once.
            let mut image = vec![0u8; (w * h * 4) as usize];
            let mut seen = vec![0u32; (w * h) as usize];
            for i in 0..g.len() {
                let tile = vec![(i % 250) as u8 + 1; (rw * rh * 4) as usize];
                let mut one = vec![0u8; (w * h * 4) as usize];
                g.copy_inner(i, &tile, &mut one);
                for (p, s) in one.chunks_exact(4).zip(seen.iter_mut()) {
                    *s += (p[0] != 0) as u32;
                }
                g.copy_inner(i, &tile, &mut image);
            }
            assert!(
                seen.iter().all(|&s| s == 1),
                "{w}x{h}: a pixel covered 0 or 2+ times"
            );
            assert!(image.iter().all(|&b| b != 0));
        }
        assert_eq!(TileGrid::new(640, 360, 1 << 20, 4).len(), 1);
        assert_eq!(TileGrid::new(3840, 2160, 800_000, 8).len(), 12);
    }
}
