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
            #[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
            pub struct $name { $( $(#[$fm])* pub $field: $fty ),* }
        )*
    };
}

include!("gpu_types.rs");

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

    #[test]
    fn layouts_are_scalar_compatible() {
        // Scalar block layout: a u64 field must sit at an 8-byte offset.
        assert_eq!(std::mem::size_of::<GPixel>(), 48);
        assert_eq!(std::mem::size_of::<HashCell>(), 32);
        assert_eq!(std::mem::size_of::<HashTestCase>(), 56);
        assert_eq!(std::mem::size_of::<GeometryInfo>(), 32);
        assert_eq!(std::mem::size_of::<FrameGlobals>() % 8, 0);
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
