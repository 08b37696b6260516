//! Custom-size screenshots rendered in the background. The shot has its own `Renderer` (its own hash map, sized
//! for the shot's pixels; the Vulkan context and the scene's acceleration structures are shared) that draws the
//! image tile by tile (`hrtao_core::tile`), one frame of one tile per viewer frame, recorded into the viewer's
//! command buffer: the window keeps drawing and navigating while the shot converges. A tile is kept once its
//! still image has converged (refinement and jittered anti-aliasing, `FrameReport::converged`, as the viewer's
//! still image), then the next one starts; the PNG is written on a background thread.
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use ash::vk;
use hrtao_core::renderer::AA_FRAMES;
use hrtao_core::tile::TileGrid;
use hrtao_core::{AoSettings, Camera, FrameDesc, Gpu, Primary, Renderer, SceneGpu};
use serde::Serialize;

/// A tile that has not converged after this many frames is kept as it is (a safety net: with refinement a tile
/// converges after `AA_FRAMES` + 1 frames).
pub const MAX_TILE_FRAMES: u32 = 64;
/// The smallest tile budget in pixels (a tiny window would otherwise cut the shot into very many tiles).
pub const MIN_SLICE_PIXELS: u64 = 32 * 1024;

/// What a finished shot did (in the `--stats` JSON of a scripted run).
#[derive(Clone, Debug, Serialize)]
pub struct ShotSummary {
    pub path: PathBuf,
    pub size: [u32; 2],
    pub tiles: usize,
    /// A tile as rendered, margins included.
    pub tile_size: [u32; 2],
    /// Frames the shot's renderer drew (all tiles).
    pub frames: u32,
    /// Frames the window presented meanwhile, and those in which the view itself was rendered.
    pub viewer_frames: u32,
    pub viewer_rendered: u32,
    pub unconverged_tiles: u32,
    pub failed_inserts: u64,
    pub hash_capacity: u32,
    pub seconds: f64,
}

/// A finished image, ready to be written.
pub struct Finished {
    pub rgba: Vec<u8>,
    pub summary: ShotSummary,
}

pub struct BackgroundShot {
    renderer: Renderer,
    /// The shot's settings (its own capacity, budget and filter) and camera (the full image's size).
    settings: AoSettings,
    camera: Camera,
    grid: TileGrid,
    path: PathBuf,
    image: Vec<u8>,
    tile: usize,
    tile_frames: u32,
    /// A frame was recorded into this viewer frame's command buffer (finish reads it back).
    pending: bool,
    frames: u32,
    pub viewer_frames: u32,
    pub viewer_rendered: u32,
    unconverged_tiles: u32,
    failed_inserts: u64,
    started: Instant,
    /// GPU milliseconds of the last frame (the viewer's frame-time target leaves them out).
    pub last_gpu_ms: f64,
}

/// Hash capacity for `pixels`: about 12 % of the pixels become cells at 4 LODs (measured at 3840×2160 on the
/// bundled scene), so half the pixel count keeps the load near 25 %; never below the viewer's own, and at most
/// 2^25 cells (1 GiB): beyond that, cells of finished tiles go stale and are reclaimed (eq. 6) for later tiles.
pub fn hash_capacity_for(pixels: u64, viewer: u32) -> u32 {
    let want = (pixels / 2)
        .next_power_of_two()
        .clamp(1024, MAX_HASH_CAPACITY as u64) as u32;
    want.max(viewer)
}

/// The largest map a screenshot allocates by itself.
pub const MAX_HASH_CAPACITY: u32 = 1 << 25;

/// À-trous iterations of a refined tile at most (the default has 5, for the first still frames).
pub const SHOT_FILTER_ITERATIONS: u32 = 3;

/// Pixels rendered around each tile: what the à-trous filter (2^i steps of 2 pixels) and the edges (1 pixel) see.
fn margin_for(settings: &AoSettings) -> u32 {
    let filter = if settings.filter.filter_iterations > 0 {
        2 * ((1u32 << settings.filter.filter_iterations.min(8)) - 1)
    } else {
        0
    };
    (filter + 1).clamp(1, 32)
}

impl BackgroundShot {
    /// A shot of `camera`'s pose at `size`, in tiles of about `slice_pixels` (a moving viewer frame's work), with
    /// the primary visibility the viewer measured faster for this scene.
    pub fn new(
        gpu: &Arc<Gpu>,
        settings: &AoSettings,
        camera: &Camera,
        size: (u32, u32),
        path: PathBuf,
        slice_pixels: u64,
        primary: Primary,
    ) -> Result<BackgroundShot> {
        let pixels = size.0 as u64 * size.1 as u64;
        let mut settings = settings.clone();
        settings.map.hash_capacity = hash_capacity_for(pixels, settings.map.hash_capacity);
        // With refinement: just enough rays per frame that a pixel has its own `still_samples` once the tile is
        // anti-aliased (more would not end it sooner). The viewer's budget follows its own resolution, and so
        // does its fraction of tracing pixels: a tile's every pixel traces (the frames carry no budget).
        if settings.still.refine {
            // A refined tile runs until its pixels have their own rays, which is what the final image shows:
            // the filter only smooths its first frames. Three iterations keep the tile margin at 15 pixels.
            settings.filter.filter_iterations = settings.filter.filter_iterations.min(SHOT_FILTER_ITERATIONS);
            settings.map.rays_per_pixel = settings.still.still_samples.div_ceil(AA_FRAMES).clamp(1, 64);
        } else {
            settings.map.rays_per_pixel = settings.map.rays_per_pixel.max(1);
        }
        let grid = TileGrid::new(
            size.0,
            size.1,
            slice_pixels.max(MIN_SLICE_PIXELS),
            margin_for(&settings),
        );
        let mut renderer = Renderer::new(gpu).context("cannot create the screenshot's renderer")?;
        renderer.set_primary(primary);
        Ok(BackgroundShot {
            renderer,
            settings,
            camera: Camera {
                width: size.0,
                height: size.1,
                ..*camera
            },
            image: vec![0; pixels as usize * 4],
            grid,
            path,
            tile: 0,
            tile_frames: 0,
            pending: false,
            frames: 0,
            viewer_frames: 0,
            viewer_rendered: 0,
            unconverged_tiles: 0,
            failed_inserts: 0,
            started: Instant::now(),
            last_gpu_ms: 0.0,
        })
    }

    pub fn tiles(&self) -> usize {
        self.grid.len()
    }

    /// Records one frame of the current tile into the viewer's command buffer.
    pub fn record(&mut self, cmd: vk::CommandBuffer, scene: &SceneGpu, scene_f: u32) -> Result<()> {
        let (tw, th) = self.grid.render_size();
        let camera = Camera {
            width: tw,
            height: th,
            ..self.camera
        };
        let frame = FrameDesc {
            tile: Some(self.grid.tile(self.tile)),
            jitter: true,
            ..FrameDesc::new(scene, scene_f, camera, &self.settings)
        };
        self.renderer.record_frame(cmd, &frame)?;
        self.pending = true;
        Ok(())
    }

    /// After the viewer's frame completed: the frame's statistics; a converged tile is copied into the image and
    /// the next one starts. Returns the image after the last tile.
    pub fn finish(&mut self) -> Result<Option<Finished>> {
        if !std::mem::take(&mut self.pending) {
            return Ok(None);
        }
        let report = self.renderer.finish_frame(0.0)?;
        self.last_gpu_ms = report.gpu_total_ms;
        self.frames += 1;
        self.tile_frames += 1;
        self.failed_inserts += report.failed_inserts as u64;
        if !report.converged && self.tile_frames < MAX_TILE_FRAMES {
            return Ok(None);
        }
        if !report.converged {
            self.unconverged_tiles += 1;
        }
        let px = self.renderer.read_rgba()?;
        self.grid.copy_inner(self.tile, &px, &mut self.image);
        log::info!(
            "screenshot tile {}/{} kept after {} frames ({}), {:.1} s so far",
            self.tile + 1,
            self.grid.len(),
            self.tile_frames,
            if report.converged {
                "converged"
            } else {
                "frame cap"
            },
            self.started.elapsed().as_secs_f64()
        );
        self.tile += 1;
        self.tile_frames = 0;
        if self.tile < self.grid.len() {
            return Ok(None);
        }
        let (tw, th) = self.grid.render_size();
        Ok(Some(Finished {
            rgba: std::mem::take(&mut self.image),
            summary: ShotSummary {
                path: self.path.clone(),
                size: [self.grid.full.0, self.grid.full.1],
                tiles: self.grid.len(),
                tile_size: [tw, th],
                frames: self.frames,
                viewer_frames: self.viewer_frames,
                viewer_rendered: self.viewer_rendered,
                unconverged_tiles: self.unconverged_tiles,
                failed_inserts: self.failed_inserts,
                hash_capacity: self.settings.map.hash_capacity,
                seconds: self.started.elapsed().as_secs_f64(),
            },
        }))
    }

    /// Done fraction: finished tiles, and the current one by its frames of the usual AA_FRAMES + 1.
    pub fn progress(&self) -> f32 {
        let current = (self.tile_frames as f32 / (AA_FRAMES + 1) as f32).min(0.95);
        ((self.tile as f32 + current) / self.grid.len().max(1) as f32).clamp(0.0, 1.0)
    }

    pub fn status(&self) -> String {
        format!(
            "{}×{}: tile {}/{}, {} frames, {:.0} s",
            self.grid.full.0,
            self.grid.full.1,
            (self.tile + 1).min(self.grid.len()),
            self.grid.len(),
            self.frames,
            self.started.elapsed().as_secs_f64()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hash_map_grows_with_the_pixels() {
        // 3840×2160: 4 M cells (about 1 M are used there), never less than the viewer's map.
        assert_eq!(hash_capacity_for(3840 * 2160, 1 << 20), 1 << 22);
        assert_eq!(hash_capacity_for(640 * 360, 1 << 20), 1 << 20);
        assert_eq!(hash_capacity_for(16384 * 16384, 1 << 20), MAX_HASH_CAPACITY);
        assert_eq!(hash_capacity_for(64, 1 << 26), 1 << 26);
        // Three filter passes (a refined tile's) reach 2 + 4 + 8 pixels; the edges one more.
        let s = {
            let mut s = AoSettings::default();
            s.filter.filter_iterations = SHOT_FILTER_ITERATIONS;
            s
        };
        assert_eq!(margin_for(&s), 15);
    }
}
