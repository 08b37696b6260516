//! How a ray-tracing pass is cut into dispatches so that none of them runs long enough to trip a GPU watchdog
//! (Windows' 2 s TDR, Linux hang checks): a pass over `width` x `height` pixels tracing up to `rays` rays per
//! pixel becomes chunks of rays `[first_ray, first_ray + ray_count)` of every pixel, and, when even one ray for
//! every pixel exceeds the bound, of bands of rows. Pure arithmetic: `renderer.rs` records one dispatch per
//! chunk (rtao.comp, ao_update.comp take the chunk in their push constants, `Chunk::push`), and the passes'
//! declared accesses order the chunks (each reads and writes what the one before wrote).

/// The most rays one dispatch may trace by default (2^25 = 33.5 M). A mid-range GPU traces about 1 G short AO
/// rays per second: 2^25 rays take ~35 ms there, so a device 50 times slower (no ray-tracing cores, a scene of
/// hundreds of millions of triangles) still ends each dispatch well inside a 2 s watchdog. Today's defaults
/// (4 rays per pixel, up to 3840x2160 = 33.2 M rays) stay one dispatch; `hrtao render --rays 1024` at 3840x2160
/// (8.5 G rays) becomes 256 dispatches of 4 rays per pixel.
pub const MAX_RAYS_PER_DISPATCH: u64 = 1 << 25;

/// The acceleration-structure traversals one AO ray may take: one, and with the sky light a second for a ray
/// open within R, traced on to infinity (sky.glsl `sky_escapes`). The plan's bound counts traversals.
pub fn traversals_per_ray(sky_light: bool) -> u64 {
    if sky_light {
        2
    } else {
        1
    }
}

/// One dispatch of a pass: rays `[first_ray, first_ray + ray_count)` of every pixel of rows
/// `[first_row, first_row + rows)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chunk {
    pub first_ray: u32,
    pub ray_count: u32,
    pub first_row: u32,
    pub rows: u32,
    /// The pass's last chunk of rays: it also traces whatever a pixel's budget has beyond `first_ray +
    /// ray_count` (a budget the plan's `rays` underestimated would otherwise be cut short).
    pub last_rays: bool,
}

/// The ray count a chunk's push constant word carries in its high 16 bits; `RAYS_REST` means "to the end of
/// the pixel's budget" (the last chunk of rays).
pub const RAYS_REST: u32 = 0xffff;

impl Chunk {
    /// Push constant word y of the chunk: `first_ray | count << 16` (both below 2^16: at most 1024 rays per
    /// pixel, four times that in adaptive sampling's second part), the count `RAYS_REST` in the last chunk.
    pub fn rays_word(&self) -> u32 {
        let count = if self.last_rays { RAYS_REST } else { self.ray_count };
        self.first_ray | (count << 16)
    }

    /// The most rays the chunk traces over a `width`-wide image when no pixel's budget exceeds the plan's.
    pub fn max_rays(&self, width: u32) -> u64 {
        self.ray_count as u64 * self.rows as u64 * width as u64
    }
}

/// Splits `width` x `height` pixels x `rays` rays per pixel into dispatches of at most `max_rays` rays: as few
/// chunks of rays as the bound allows (every pixel's rays in one dispatch when the whole pass fits), and bands
/// of rows only when one ray per pixel over the whole image is already over it. A single row at one ray is the
/// smallest dispatch: it exceeds `max_rays` only for a bound below the image width (never for the default,
/// which is above the largest width, 16384). No pixel or ray: no dispatch.
pub fn plan(width: u32, height: u32, rays: u32, max_rays: u64) -> Vec<Chunk> {
    if width == 0 || height == 0 || rays == 0 {
        return Vec::new();
    }
    let max_rays = max_rays.max(1);
    let pixels = width as u64 * height as u64;
    let rays_per_chunk = (max_rays / pixels).clamp(1, rays as u64) as u32;
    let rows_per_band = if rays_per_chunk == 1 {
        (max_rays / width as u64).clamp(1, height as u64) as u32
    } else {
        height
    };
    let mut chunks = Vec::new();
    let mut first_ray = 0;
    while first_ray < rays {
        let ray_count = rays_per_chunk.min(rays - first_ray);
        let last_rays = first_ray + ray_count == rays;
        let mut first_row = 0;
        while first_row < height {
            let rows = rows_per_band.min(height - first_row);
            chunks.push(Chunk {
                first_ray,
                ray_count,
                first_row,
                rows,
                last_rays,
            });
            first_row += rows;
        }
        first_ray += ray_count;
    }
    chunks
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every (row, ray) of the pass in exactly one chunk (columns are never split).
    fn assert_covers(chunks: &[Chunk], height: u32, rays: u32) {
        let mut seen = vec![0u8; height as usize * rays as usize];
        for c in chunks {
            for row in c.first_row..c.first_row + c.rows {
                for ray in c.first_ray..c.first_ray + c.ray_count {
                    seen[(row * rays + ray) as usize] += 1;
                }
            }
        }
        let wrong = seen.iter().filter(|&&n| n != 1).count();
        assert_eq!(wrong, 0, "(row, ray) pairs covered other than once");
    }

    #[test]
    fn a_4k_render_at_1024_rays_stays_within_the_bound() {
        let (w, h, rays) = (3840, 2160, 1024);
        let chunks = plan(w, h, rays, MAX_RAYS_PER_DISPATCH);
        let worst = chunks.iter().map(|c| c.max_rays(w)).max().unwrap();
        assert!(worst <= MAX_RAYS_PER_DISPATCH, "a dispatch of {worst} rays");
        assert_covers(&chunks, h, rays);
        // 8.5 G rays in 4-ray chunks: as few dispatches as the bound allows.
        assert_eq!(chunks.len(), 256);
        assert!(chunks.iter().all(|c| c.rows == h));
        assert_eq!(chunks.iter().filter(|c| c.last_rays).count(), 1);
    }

    #[test]
    fn the_defaults_stay_one_dispatch() {
        // 4 rays per pixel (settings/map.rs) at 3840x2160 and below.
        for (w, h) in [(1920, 1080), (3840, 2160)] {
            let chunks = plan(w, h, 4, MAX_RAYS_PER_DISPATCH);
            assert_eq!(chunks.len(), 1, "{w}x{h}");
            assert_covers(&chunks, h, 4);
        }
    }

    #[test]
    fn an_image_over_the_bound_at_one_ray_splits_by_rows() {
        // 16384x16384 = 268 M pixels: one ray each is 8 bounds' worth.
        let (w, h, rays) = (16384, 16384, 3);
        let chunks = plan(w, h, rays, MAX_RAYS_PER_DISPATCH);
        assert!(chunks.iter().all(|c| c.max_rays(w) <= MAX_RAYS_PER_DISPATCH));
        assert!(chunks.iter().all(|c| c.ray_count == 1));
        assert_covers(&chunks, h, rays);
        assert_eq!(chunks.len(), 3 * 8);
        // Every dispatch within the portable 65,535 work groups per dimension (8x8 groups, crate::gpu).
        let group = crate::gpu::WORKGROUP_SIZE;
        assert!(chunks
            .iter()
            .all(|c| w.div_ceil(group) <= 65535 && c.rows.div_ceil(group) <= 65535));
    }

    #[test]
    fn small_bounds_split_rays_then_rows() {
        // 64x36 at 256 rays with 16 rays per pixel per dispatch; then a bound below one ray per pixel.
        let chunks = plan(64, 36, 256, 64 * 36 * 16);
        assert_eq!(chunks.len(), 16);
        assert_covers(&chunks, 36, 256);
        let chunks = plan(64, 36, 5, 64 * 10);
        assert!(chunks.iter().all(|c| c.max_rays(64) <= 640));
        assert_covers(&chunks, 36, 5);
        assert_eq!(chunks.len(), 5 * 4);
    }

    #[test]
    fn the_rays_word_packs_the_chunk() {
        let c = Chunk {
            first_ray: 12,
            ray_count: 4,
            first_row: 0,
            rows: 1,
            last_rays: false,
        };
        assert_eq!(c.rays_word(), 12 | 4 << 16);
        let last = Chunk { last_rays: true, ..c };
        assert_eq!(last.rays_word() >> 16, RAYS_REST);
    }
}
