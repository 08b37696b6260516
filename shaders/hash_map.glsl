// The world-space hash map (paper §1): find-or-insert with linear probing, bounded probe length, every slot
// wrapped into the table, lazy removal of cells of an old F (eq. 6) or unused for the cache lifetime (in seconds,
// turned into `lifetime_frames` frames by the host: hash_map/lifetime.rs).
//
// A cell's checksum and its "last used" frame share one 64-bit word (`HashCell::stamp`), so claiming a cell
// (free or reclaimable) and re-stamping a found one are each a single atomicCompSwap: no thread can take over
// a cell between another thread's claim and its stamp. Within a dispatch the frame is fixed, so a cell only
// ever goes from reclaimable to live, never back: the candidate a probe picks can be lost only to a claim.
// Modelled on the CPU and checked under every interleaving in tests/hash_map_model.rs.
#ifndef HRTAO_HASH_MAP_GLSL
#define HRTAO_HASH_MAP_GLSL
#include "hash.glsl"
#include "sky.glsl"

// Records an out-of-range slot in assertion mode (FLAG_CHECK_BOUNDS); returns true when `slot` is usable.
bool slot_in_bounds(uint slot) {
    bool ok = slot < g.hash_capacity;
    if (!ok && (g.flags & FLAG_CHECK_BOUNDS) != 0u) stat_add(STAT_BOUNDS_VIOLATIONS, 1u);
    return ok;
}

uint64_t make_stamp(uint checksum, uint frame) { return packUint2x32(uvec2(checksum, frame)); }
uint stamp_checksum(uint64_t s) { return unpackUint2x32(s).x; }
uint stamp_frame(uint64_t s) { return unpackUint2x32(s).y; }

// Atomic read of a cell's stamp (another thread may claim it in the same dispatch).
// An atomic load (not a read-modify-write: a shared cell's line stays shared between the cores that read it).
uint64_t load_stamp(CellRef cells, uint slot) {
    return atomicLoad(cells.v[slot].stamp, gl_ScopeDevice, gl_StorageSemanticsBuffer, gl_SemanticsRelaxed);
}

// eq. (6)'s lazy removal: a cell may go to another key when it was last used before the first frame of the
// current F (its F is old: no key of the current F can reach it) or longer than the cache lifetime ago (more than
// `lifetime_frames` frames: the host counts the frames of the last `cache_lifetime_s` seconds).
// Frame numbers wrap: ages are unsigned differences.
bool stamp_reclaimable(uint64_t s) {
    uint age = g.frame_index - stamp_frame(s);
    return age > g.frame_index - g.f_start_frame || age > g.lifetime_frames;
}

// Local edits (ours): the epoch of the region holding cell `c`, and the cell's key with it.
layout(buffer_reference, scalar) buffer RegionRef { uint v[]; };
uint region_epoch(ivec3 c, int lod) {
    if ((g.flags & FLAG_REGION_EPOCHS) == 0u) return 0u;
    return RegionRef(g.regions).v[region_index(c, lod, g.region_lod)];
}
CellKey region_cell_key(ivec3 c, int lod, ivec3 nq) {
    return cell_key_at(c, lod, nq, g.scene_f, region_epoch(c, lod), g.hash_capacity);
}
// Whether the last local edit is new to the pixels this frame draws: made this frame, or, when frames draw
// slices, within the round of slices since (`edit_window` frames: each pixel is drawn once in them).
bool edit_within(RegionRef t, uint frames) {
    return g.frame_index - t.v[REGION_COUNT] < max(frames, 1u);
}

bool edit_is_new(RegionRef t) {
    return edit_within(t, g.edit_window);
}

// Whether a local edit changed anything that the pixels of this frame have not seen.
bool edited_this_frame() {
    RegionRef t = RegionRef(g.regions);
    return edit_is_new(t) && t.v[REGION_COUNT + 1u] > 0u;
}

// True when the last local edit, made less than `frames` frames ago, changed geometry within `reach` of `p`
// (its boxes follow the epochs).
bool edited_within(vec3 p, float reach, uint frames) {
    RegionRef t = RegionRef(g.regions);
    if (!edit_within(t, frames)) return false;
    uint n = min(t.v[REGION_COUNT + 1u], MAX_EDIT_BOXES);
    for (uint i = 0u; i < n; ++i) {
        uint w = REGION_COUNT + 4u + 8u * i;
        vec3 lo = uintBitsToFloat(uvec3(t.v[w], t.v[w + 1u], t.v[w + 2u]));
        vec3 hi = uintBitsToFloat(uvec3(t.v[w + 4u], t.v[w + 5u], t.v[w + 6u]));
        if (length(max(max(lo - p, p - hi), vec3(0.0))) <= reach) return true;
    }
    return false;
}

// True when a local edit these pixels have not seen changed geometry within `reach` of `p`.
bool edited_near(vec3 p, float reach) {
    return edited_within(p, reach, g.edit_window);
}

// True while a neighbour at `p` may still hold, in the slot of either parity (composite.comp's evidence and
// prior), what it found before a local edit within `reach`: until it has drawn twice since, two edit windows
// (in slices, a neighbour drawn before the edit in its round rewrites the other parity's slot only in the
// round after).
bool neighbour_slots_stale(vec3 p, float reach) {
    return edited_within(p, reach, 2u * max(g.edit_window, 1u));
}

// The longest probe run: most probes end at their first slot, so look before the atomic (which every pixel of
// every level would otherwise contend for on one counter).
void note_probe(uint length) {
    StatsRef stats = StatsRef(g.stats);
    if (atomicLoad(stats.counters[STAT_MAX_PROBE], gl_ScopeDevice, gl_StorageSemanticsBuffer, gl_SemanticsRelaxed)
        < length) {
        atomicMax(stats.counters[STAT_MAX_PROBE], length);
    }
}

// Empties the counters of a cell this thread has just claimed (its stamp already names the new key).
void reset_counters(CellRef cells, uint slot) {
    atomicExchange(cells.v[slot].samples, 0u);
    atomicExchange(cells.v[slot].unoccluded, 0u);
    atomicExchange(cells.v[slot].qmc_index, 0u);
    atomicExchange(cells.v[slot].near_traced, 0u);
    atomicExchange(cells.v[slot].near_open, 0u);
    if (sky_on()) sky_cell_reset(slot);
}

// How many times a probe restarts after losing its candidate slot to another key (bounded work per thread).
const uint PROBE_ATTEMPTS = 4u;

// Returns the slot holding `key`, inserting it when absent; INVALID_CELL when the probe limit is reached.
// The whole probe run is scanned first (to a free slot or max_probe): a key that lives further down the run
// is found and kept, and a slot is claimed only when the key is absent. While the table has room
// (FLAG_MAP_HAS_ROOM) the claim takes the free slot that ends the run, and a reclaimable cell met before it keeps
// its key and AO (a revisit past the cache lifetime still finds it); past the room, or when the run has no free
// slot within max_probe, it takes the first reclaimable slot, so the table recycles. Either way the key lands
// within its run, before its first free slot: lookups, which scan to the first free slot, find it.
uint find_or_insert(CellKey key) {
    CellRef cells = CellRef(g.hash_cells);
    uint mask = g.hash_capacity - 1u;
    uint64_t mine = make_stamp(key.checksum, g.frame_index);
    bool room = (g.flags & FLAG_MAP_HAS_ROOM) != 0u;
    for (uint attempt = 0u; attempt < PROBE_ATTEMPTS; ++attempt) {
        uint stale = INVALID_CELL;   // the first reclaimable slot of the run
        uint free_slot = INVALID_CELL;   // the free slot ending the run
        uint64_t stale_stamp = uint64_t(0);
        uint64_t free_stamp = uint64_t(0);
        uint stale_length = 0u;
        uint free_length = 0u;
        bool lost = false;
        for (uint i = 0u; i < g.max_probe; ++i) {
            uint slot = (key.slot + i) & mask;
            if (!slot_in_bounds(slot)) return INVALID_CELL;
            uint64_t s = load_stamp(cells, slot);
            uint c = stamp_checksum(s);
            if (c == key.checksum) {
                // Found: re-stamp it as used this frame, unless another key has just reclaimed it.
                while (stamp_frame(s) != g.frame_index) {
                    uint64_t prev = atomicCompSwap(cells.v[slot].stamp, s, mine);
                    if (prev == s) break;
                    s = prev;
                }
                if (stamp_checksum(s) == key.checksum) {
                    note_probe(i + 1u);
                    return slot;
                }
                lost = true;   // reclaimed by another key between our read and our stamp: probe again
                break;
            }
            if (c == EMPTY_CELL) {
                free_slot = slot;
                free_stamp = s;
                free_length = i + 1u;
                break;   // no deletions: a free slot ends the key's probe run
            }
            if (stale == INVALID_CELL && stamp_reclaimable(s)) {
                stale = slot;
                stale_stamp = s;
                stale_length = i + 1u;
            }
        }
        if (lost) continue;
        bool take_free = free_slot != INVALID_CELL && (room || stale == INVALID_CELL);
        uint candidate = take_free ? free_slot : stale;
        uint64_t expected = take_free ? free_stamp : stale_stamp;
        uint length = take_free ? free_length : stale_length;
        if (candidate == INVALID_CELL) break;
        uint64_t prev = atomicCompSwap(cells.v[candidate].stamp, expected, mine);
        if (prev == expected) {
            reset_counters(cells, candidate);
            // Before any later pass looks the key up (find_cell), its home slot bounds the run to it.
            atomicMax(cells.v[key.slot].probe_run, length);
            if (stamp_checksum(expected) == EMPTY_CELL) {
                stat_add(STAT_CELLS_INSERTED, 1u);
                stat_add(STAT_OCCUPIED, 1u);
            } else {
                stat_add(STAT_RECLAIMED, 1u);
            }
            note_probe(length);
            return candidate;
        }
        if (stamp_checksum(prev) == key.checksum) {
            // Another thread inserted the same key there first: share its cell.
            note_probe(length);
            return candidate;
        }
        // Another key took the candidate: probe again (the table only gained live cells).
    }
    stat_add(STAT_FAILED_INSERTS, 1u);
    return INVALID_CELL;
}

// Returns the slot holding `key`, or INVALID_CELL when absent (read only). Scans the longest run any key homed
// at the key's slot was claimed at (`HashCell::probe_run`, set by find_or_insert before the passes that look up),
// and stops early at a free slot: slots are reclaimed but never emptied, so on a table crowded with old cells an
// absent key would otherwise scan all max_probe slots, and the resolve looks up 8 neighbours per pixel, most of
// them absent where the view moves into new cells (walking: 8-12x an orbit's resolve on lavapipe).
uint find_cell(CellKey key) {
    CellRef cells = CellRef(g.hash_cells);
    uint mask = g.hash_capacity - 1u;
    if (!slot_in_bounds(key.slot)) return INVALID_CELL;
    uint run = min(cells.v[key.slot].probe_run, g.max_probe);
    // In assertion mode (FLAG_CHECK_BOUNDS) the scan goes on to max_probe and a key found past its home's run
    // counts as a bounds violation.
    bool check = (g.flags & FLAG_CHECK_BOUNDS) != 0u;
    for (uint i = 0u; i < (check ? g.max_probe : run); ++i) {
        uint slot = (key.slot + i) & mask;
        if (!slot_in_bounds(slot)) return INVALID_CELL;
        uint c = stamp_checksum(cells.v[slot].stamp);
        if (c == key.checksum) {
            if (i >= run) stat_add(STAT_BOUNDS_VIOLATIONS, 1u);
            return slot;
        }
        if (c == EMPTY_CELL) return INVALID_CELL;
    }
    return INVALID_CELL;
}

// The LOD of a pixel with hit distance d (eq. 2-3): s_w = s_w_base + d * s_w_per_distance (one of the two terms
// is 0: perspective or orthographic, see FrameGlobals), bounded by s_w_max.
int pixel_lod(float d) {
    return lod_of(min(g.s_w_base + d * g.s_w_per_distance, g.s_w_max), g.log2_s_min);
}

#endif
