//! The GPU hash (shaders/hash.glsl) equals the CPU mirror (src/hash.rs) bit for bit.
mod common;
use common::*;
use hrtao_core::gpu::HashTestCase;
use hrtao_core::{hash, AoSettings, SceneGpu};
use hrtao_scene::glam::Vec3;

/// A small deterministic generator (no rand dependency).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
}

#[test]
fn gpu_hash_matches_cpu_bit_for_bit() {
    let gpu = gpu();
    let scene = scene_of(vec![floor()]);
    let sg = SceneGpu::new(&gpu, &scene).unwrap();
    let settings = {
        let mut s = AoSettings::default();
        s.map.hash_capacity = 1 << 16;
        s.map.s_nd = 3.0;
        s
    };
    let mut r = Headless::new(&gpu, 16, 16, settings.clone()).unwrap();
    let mut rng = Lcg(7);
    let mut cases = Vec::new();
    for i in 0..4096u32 {
        // Positions from millimetres to kilometres, far from the origin too; normals of every direction;
        // feature sizes over 20 octaves; F values incl. wrap-around.
        let scale = 10f32.powf(rng.range(-3.0, 3.0));
        let offset = if i % 3 == 0 { 1000.0 } else { 0.0 };
        let p = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * scale + offset;
        let n =
            Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)).normalize_or_zero();
        let s_w = 10f32.powf(rng.range(-4.0, 2.0));
        let frame = match i % 4 {
            0 => 0,
            1 => i,
            2 => u32::MAX - i,
            _ => (rng.next() * 1e6) as u32,
        };
        cases.push(HashTestCase {
            position: p.to_array(),
            s_w,
            normal: n.to_array(),
            scene_f: frame,
            epoch: if i % 5 == 0 { 0 } else { rng.next().to_bits() },
            lod_offset: i % 4,
            ..Default::default()
        });
    }
    let out = r.hash_on_gpu(&sg, &cases).unwrap();
    let l2 = hash::log2_s_min(settings.map.s_min);
    let mut mismatches = 0;
    for (c, g) in cases.iter().zip(&out) {
        let lod = hash::lod_of(c.s_w, l2) + c.lod_offset as i32;
        let key = hash::cell_key(
            Vec3::from(c.position),
            Vec3::from(c.normal),
            lod,
            hash::NormalBins {
                s_nd: settings.map.s_nd,
                offset: settings.map.normal_offset(),
            },
            c.scene_f,
            c.epoch,
            settings.map.hash_capacity,
        );
        let region = hash::region_index(hash::cell_coord(Vec3::from(c.position), lod), lod, r.region_lod());
        if (g.lod, g.index, g.checksum, g.region) != (lod, key.slot, key.checksum, region) {
            if mismatches < 5 {
                eprintln!(
                    "mismatch: {c:?}\n  gpu lod {} slot {} check {} region {}\n  cpu lod {lod} slot {} check {} region {region}",
                    g.lod, g.index, g.checksum, g.region, key.slot, key.checksum
                );
            }
            mismatches += 1;
        }
    }
    assert_eq!(mismatches, 0, "{mismatches} of {} cases differ", cases.len());
    // The keys spread over the table (not a constant function).
    let distinct: std::collections::HashSet<u32> = out.iter().map(|c| c.index).collect();
    assert!(distinct.len() > 3000, "only {} distinct slots", distinct.len());
    assert_clean(&gpu);
}
