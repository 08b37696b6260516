// The world-space hash map (paper §1): find-or-insert with linear probing on atomicCompSwap of the checksum,
// bounded probe length, every slot wrapped into the table, lazy removal of cells of an old F (eq. 6) or
// untouched for `stale_frames` frames.
#ifndef HRTAO_HASH_MAP_GLSL
#define HRTAO_HASH_MAP_GLSL
#include "hash.glsl"

void stat_add(uint which, uint v) { atomicAdd(StatsRef(g.stats).counters[which], v); }

// Records an out-of-range slot in assertion mode (FLAG_CHECK_BOUNDS); returns true when `slot` is usable.
bool slot_in_bounds(uint slot) {
    bool ok = slot < g.hash_capacity;
    if (!ok && (g.flags & FLAG_CHECK_BOUNDS) != 0u) stat_add(STAT_BOUNDS_VIOLATIONS, 1u);
    return ok;
}

// A cell may be reused for another key when it belongs to an old F or has not been touched for a while.
bool cell_reclaimable(HashCell c) {
    return c.scene_frame != g.scene_frame || (g.frame_counter - c.last_frame) > g.stale_frames;
}

void reset_cell(CellRef cells, uint slot) {
    atomicExchange(cells.v[slot].samples, 0u);
    atomicExchange(cells.v[slot].unoccluded, 0u);
    atomicExchange(cells.v[slot].qmc_index, 0u);
    cells.v[slot].last_frame = g.frame_counter;
    cells.v[slot].scene_frame = g.scene_frame;
}

// Returns the slot holding `key`, inserting it when absent; INVALID_CELL when the probe limit is reached.
uint find_or_insert(CellKey key) {
    CellRef cells = CellRef(g.hash_cells);
    uint mask = g.hash_capacity - 1u;
    for (uint i = 0u; i < g.max_probe; ++i) {
        uint slot = (key.slot + i) & mask;
        if (!slot_in_bounds(slot)) return INVALID_CELL;
        uint prev = atomicCompSwap(cells.v[slot].checksum, EMPTY_CELL, key.checksum);
        if (prev == EMPTY_CELL) {
            reset_cell(cells, slot);
            stat_add(STAT_CELLS_INSERTED, 1u);
            stat_add(STAT_OCCUPIED, 1u);
            atomicMax(StatsRef(g.stats).counters[STAT_MAX_PROBE], i + 1u);
            return slot;
        }
        if (prev == key.checksum) {
            cells.v[slot].last_frame = g.frame_counter;
            atomicMax(StatsRef(g.stats).counters[STAT_MAX_PROBE], i + 1u);
            return slot;
        }
        if (cell_reclaimable(cells.v[slot])) {
            // Take the stale cell over, unless another thread changed it first.
            if (atomicCompSwap(cells.v[slot].checksum, prev, key.checksum) == prev) {
                reset_cell(cells, slot);
                stat_add(STAT_RECLAIMED, 1u);
                atomicMax(StatsRef(g.stats).counters[STAT_MAX_PROBE], i + 1u);
                return slot;
            }
        }
    }
    stat_add(STAT_FAILED_INSERTS, 1u);
    return INVALID_CELL;
}

// Returns the slot holding `key`, or INVALID_CELL when absent (read only; stops at the first free slot,
// which linear probing without deletions guarantees ends the key's run).
uint find_cell(CellKey key) {
    CellRef cells = CellRef(g.hash_cells);
    uint mask = g.hash_capacity - 1u;
    for (uint i = 0u; i < g.max_probe; ++i) {
        uint slot = (key.slot + i) & mask;
        if (!slot_in_bounds(slot)) return INVALID_CELL;
        uint c = cells.v[slot].checksum;
        if (c == key.checksum) return slot;
        if (c == EMPTY_CELL) return INVALID_CELL;
    }
    return INVALID_CELL;
}

// The LOD of pixel with hit distance d (eq. 2-3).
int pixel_lod(float d) {
    return lod_of(d * g.s_w_per_distance, g.log2_s_min);
}

#endif
