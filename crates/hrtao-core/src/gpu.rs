//! Rust side of the GPU-visible types: `gpu_types.rs` expanded into `#[repr(C)]` Pod structs and constants.
//! `build.rs` expands the same file into GLSL, so both languages share one definition.

macro_rules! gpu_consts {
    ($( $(#[$m:meta])* $name:ident : $ty:ty = $val:expr; )*) => {
        $( $(#[$m])* pub const $name: $ty = $val; )*
    };
}

macro_rules! gpu_structs {
    ($( $(#[$m:meta])* struct $name:ident { $( $(#[$fm:meta])* $field:ident : $fty:ty ),* $(,)? } )*) => {
        $(
            $(#[$m])*
            #[repr(C)]
            #[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
            pub struct $name { $( $(#[$fm])* pub $field: $fty ),* }

            /// All zero (as `bytemuck::Zeroable`: arrays of any length).
            impl Default for $name {
                fn default() -> Self {
                    bytemuck::Zeroable::zeroed()
                }
            }
        )*
    };
}

include!("gpu_types.rs");

/// A unit normal in one u32: octahedral mapping to 16-bit signed-normalised coordinates, x in the low half
/// (GLSL's `packSnorm2x16`); `shaders/normal_pack.glsl` is the GPU side (`unpack_normal`), and the GPU tests of
/// tests/shading_normals.rs (normals packed here, unpacked there) hold the two to agree. A zero or non-finite
/// normal packs as +z.
pub fn pack_normal(n: [f32; 3]) -> u32 {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    if !(l1.is_finite() && l1 > 0.0) {
        return pack_normal([0.0, 0.0, 1.0]);
    }
    let (x, y, z) = (n[0] / l1, n[1] / l1, n[2] / l1);
    let (ex, ey) = if z >= 0.0 {
        (x, y)
    } else {
        // oct_wrap: (1 - |v.yx|) * sign(v), with sign(0) = +1.
        let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
        ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y))
    };
    let snorm = |v: f32| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    snorm(ex) | (snorm(ey) << 16)
}

/// `pack_normal`'s inverse (GLSL's `unpack_normal`), unit length.
pub fn unpack_normal(u: u32) -> [f32; 3] {
    let unorm = |h: u32| ((h as u16 as i16) as f32 / 32767.0).max(-1.0);
    let (ex, ey) = (unorm(u & 0xffff), unorm(u >> 16));
    let mut n = [ex, ey, 1.0 - ex.abs() - ey.abs()];
    if n[2] < 0.0 {
        let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
        n[0] = (1.0 - ey.abs()) * sign(ex);
        n[1] = (1.0 - ex.abs()) * sign(ey);
    }
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    [n[0] / len, n[1] / len, n[2] / len]
}

impl HashCell {
    /// The checksum half of the stamp (`EMPTY_CELL` for a free cell).
    pub fn checksum(&self) -> u32 {
        self.stamp as u32
    }

    /// The `frame_index` of the last frame that used the cell.
    pub fn last_frame(&self) -> u32 {
        (self.stamp >> 32) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Packed normals come back within 1e-4 of the original over the sphere, both octahedral halves.
    #[test]
    fn normals_pack_and_unpack() {
        for i in 0..2000 {
            // A Fibonacci sphere.
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 2000.0;
            let r = (1.0 - z * z).sqrt();
            let phi = i as f32 * 2.399_963;
            let n = [r * phi.cos(), r * phi.sin(), z];
            let m = unpack_normal(pack_normal(n));
            let err = (0..3).map(|k| (n[k] - m[k]).abs()).fold(0.0, f32::max);
            assert!(err < 1e-4, "{n:?} -> {m:?}");
        }
        assert_eq!(unpack_normal(pack_normal([0.0; 3])), [0.0, 0.0, 1.0]);
        assert_eq!(unpack_normal(pack_normal([f32::NAN, 0.0, 1.0])), [0.0, 0.0, 1.0]);
    }

    #[test]
    fn layouts_are_scalar_compatible() {
        // Scalar block layout: a u64 field must sit at an 8-byte offset.
        assert_eq!(std::mem::size_of::<GPixel>(), 44);
        assert_eq!(std::mem::size_of::<HashCell>(), 32);
        assert_eq!(std::mem::size_of::<HashTestCase>(), 56);
        assert_eq!(std::mem::size_of::<GeometryInfo>(), 40);
        assert_eq!(std::mem::size_of::<FrameGlobals>() % 8, 0);
        // Every 64-bit atomic sits at an 8-byte offset from a buffer's start (Buffer::new checks that each
        // buffer's address is 8-byte aligned): a misaligned one is undefined on a GPU, though lavapipe copes.
        // HashCell::stamp (compare-and-swap, hash_map.glsl) in every element of the table;
        assert_eq!(std::mem::offset_of!(HashCell, stamp) % 8, 0);
        assert_eq!(std::mem::size_of::<HashCell>() % 8, 0);
        // FrameStats::rays (atomicAdd, common.glsl `rays_add`);
        assert_eq!(std::mem::offset_of!(FrameStats, rays) % 8, 0);
        // the sky cells' int64 sums (sky.glsl `sky_cell_add`) and an addition's fitted sums (declared with
        // buffer_reference_align = 8) start their buffers.
        assert_eq!(std::mem::offset_of!(FrameGlobals, gbuffer) % 8, 0);
        assert_eq!(
            std::mem::offset_of!(FrameStats, rays),
            STAT_COUNT as usize * 4,
            "the u64 ray counters follow the u32 counters at an 8-byte offset"
        );
        assert_eq!(
            std::mem::size_of::<FrameStats>(),
            STAT_COUNT as usize * 4 + RAYS_COUNT as usize * 8
        );
    }
}
