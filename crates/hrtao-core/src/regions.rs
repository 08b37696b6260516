//! Local edits (ours, docs/algorithm.md): the region epoch table that extends eq. (6).
//!
//! The paper bumps F on every scene edit, so every cell of the map becomes unreachable. Here each LOD's cells
//! are grouped into cubic regions two cells across (hash.glsl `region_index`; all levels finer than the largest
//! finest cell share one grid), hashed into REGION_COUNT epochs, and a cell's key includes the epoch of its
//! region (hash.glsl `cell_key_at`). A point's AO can change only if changed geometry lies within the AO radius
//! R of it, so an edit bumps, on every grid, the epochs of the regions that meet its old and new bounds grown
//! by R: exactly the cells whose AO can change (and their region neighbours) get new, empty keys; all others
//! keep serving pixels. Hash collisions between regions only invalidate more than needed. After the epochs the
//! buffer holds the boxes of the last edit and its frame index: the composite restarts the still accumulation
//! of the pixels within reach of them, exactly.
use std::sync::Arc;

use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;

use crate::buffer::Buffer;
use crate::context::Gpu;
use crate::error::Result;
use crate::gpu::{LOD_COUNT, MAX_EDIT_BOXES, REGION_COUNT};
use crate::hash;

/// At most this many regions are bumped by one edit (an eighth of the table, so far regions rarely share an
/// entry with them); a larger change invalidates the whole map (F, eq. 6).
pub const MAX_REGIONS_PER_EDIT: u64 = REGION_COUNT as u64 / 8;

/// At most this many regions, counted per box (overlaps counted again), are listed for one edit.
const LISTED_REGIONS_PER_EDIT: u64 = 8 * MAX_REGIONS_PER_EDIT;

pub struct RegionTable {
    buffer: Buffer,
    /// The GPU layout: REGION_COUNT epochs; the last edit's frame index and box count and two unused words;
    /// MAX_EDIT_BOXES boxes as (min.xyz, 0, max.xyz, 0) floats.
    table: Vec<u32>,
    dirty: bool,
    /// Some epoch is not 0.
    edited: bool,
    /// The LOD of the largest finest cell: grids region_lod ..= region_lod + LOD_COUNT - 1.
    pub region_lod: i32,
}

impl RegionTable {
    pub fn new(gpu: &Arc<Gpu>) -> Result<RegionTable> {
        let buffer = Buffer::new(
            gpu,
            "region epochs",
            Self::WORDS as u64 * 4,
            MemoryLocation::CpuToGpu,
            vk::BufferUsageFlags::empty(),
        )?;
        let mut t = RegionTable {
            buffer,
            table: vec![0; Self::WORDS],
            dirty: true,
            edited: false,
            region_lod: 0,
        };
        t.upload()?;
        Ok(t)
    }

    const WORDS: usize = REGION_COUNT as usize + 4 + 8 * MAX_EDIT_BOXES as usize;

    pub fn address(&self) -> u64 {
        self.buffer.address
    }

    /// `region_lod` for finest cells of at most `s_w_max` (eq. 2-3).
    pub fn region_lod_for(s_w_max: f32, log2_s_min: i32) -> i32 {
        hash::lod_of(s_w_max, log2_s_min)
    }

    /// Whether some epoch is not 0 (else every cell key is the paper's, and shaders skip the table).
    pub fn any_edit(&self) -> bool {
        self.edited
    }

    /// The epoch of entry `i`.
    pub fn epoch(&self, i: u32) -> u32 {
        self.table[i as usize]
    }

    /// Bumps, on every grid, the epochs of the regions that meet a box of `boxes` grown by `reach` (the AO
    /// radius), and marks them edited at `frame`. Returns false (and changes nothing) when that is more than
    /// MAX_REGIONS_PER_EDIT entries of the table or a box is not finite: the caller invalidates globally then.
    pub fn invalidate(&mut self, boxes: &[(Vec3, Vec3)], reach: f32, frame: u32) -> bool {
        // Boxes may overlap (a tilted plane's columns grown by R): the limit is on distinct entries, and the
        // sum over boxes only bounds the work of listing them.
        let mut ranges = Vec::new();
        let mut count = 0u64;
        for grid in self.region_lod..self.region_lod + LOD_COUNT as i32 {
            let edge = hash::cell_size(grid + 1);
            for &(lo, hi) in boxes {
                let (lo, hi) = (lo - Vec3::splat(reach), hi + Vec3::splat(reach));
                if !(lo.is_finite() && hi.is_finite()) || lo.cmpgt(hi).any() {
                    return false;
                }
                let (a, b) = ((lo / edge).floor(), (hi / edge).floor());
                let n = (b - a + Vec3::ONE).as_dvec3();
                count = count.saturating_add((n.x * n.y * n.z).min(1e18) as u64);
                if count > LISTED_REGIONS_PER_EDIT {
                    return false;
                }
                ranges.push((grid, a.as_ivec3(), b.as_ivec3()));
            }
        }
        let mut touched = std::collections::BTreeSet::new();
        for (grid, a, b) in ranges {
            for z in a.z..=b.z {
                for y in a.y..=b.y {
                    for x in a.x..=b.x {
                        touched.insert(hash::region_entry(glam::IVec3::new(x, y, z), grid));
                    }
                }
            }
        }
        if touched.len() as u64 > MAX_REGIONS_PER_EDIT {
            return false;
        }
        for i in touched {
            let e = &mut self.table[i as usize];
            *e = e.wrapping_add(1).max(1);
            self.edited = true;
        }
        // The edit's boxes (several edits before one frame add up; beyond MAX_EDIT_BOXES they merge).
        let header = REGION_COUNT as usize;
        let mut list: Vec<(Vec3, Vec3)> = Vec::new();
        if self.table[header] == frame {
            for i in 0..self.table[header + 1] as usize {
                let w = &self.table[header + 4 + 8 * i..header + 12 + 8 * i];
                let v = |k: usize| {
                    Vec3::new(
                        f32::from_bits(w[k]),
                        f32::from_bits(w[k + 1]),
                        f32::from_bits(w[k + 2]),
                    )
                };
                list.push((v(0), v(4)));
            }
        }
        list.extend_from_slice(boxes);
        if list.len() > MAX_EDIT_BOXES as usize {
            let all = list
                .iter()
                .fold(list[0], |(a, b), &(lo, hi)| (a.min(lo), b.max(hi)));
            list = vec![all];
        }
        self.table[header] = frame;
        self.table[header + 1] = list.len() as u32;
        for (i, (lo, hi)) in list.iter().enumerate() {
            let w = &mut self.table[header + 4 + 8 * i..header + 12 + 8 * i];
            for k in 0..3 {
                w[k] = lo[k].to_bits();
                w[4 + k] = hi[k].to_bits();
            }
        }
        self.dirty = true;
        true
    }

    /// Forgets every local edit (all epochs 0: the paper's keys), e.g. when the map is cleared.
    pub fn reset(&mut self) {
        self.table.fill(0);
        self.edited = false;
        self.dirty = true;
    }

    /// The table changed since the last `upload`.
    pub fn dirty(&self) -> bool {
        self.dirty
    }

    /// Copies the table to the GPU if it changed (between frames: no frame that reads it may be in flight).
    pub fn upload(&mut self) -> Result<()> {
        if self.dirty {
            self.buffer.write(&self.table)?;
            self.dirty = false;
        }
        Ok(())
    }
}
