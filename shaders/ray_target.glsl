// Which pixels trace AO rays this frame, and into which cell (paper §3, §6). Shared by cell_finder.comp (which
// queues them) and ao_update.comp.
#ifndef HRTAO_RAY_TARGET_GLSL
#define HRTAO_RAY_TARGET_GLSL
#include "hash_map.glsl"

// The finest of the pixel's cells that exists (inserts may fail under overload) in `first`; true when that
// cell still takes rays (its QMC sequence has not reached max_samples).
bool ray_target(GPixel px, PixelCells pc, out uint first) {
    first = LOD_COUNT;
    if (px.t < 0.0 || g.rays_per_pixel == 0u) return false;
    first = 0u;
    while (first < LOD_COUNT && pc.cells[first] == INVALID_CELL) first++;
    if (first == LOD_COUNT) return false;
    uint target = pc.cells[first];
    if (!slot_in_bounds(target)) return false;
    // Atomic: in the cell finder another pixel may be claiming (and resetting) the cell in the same dispatch.
    uint claimed = atomicLoad(CellRef(g.hash_cells).v[target].qmc_index, gl_ScopeDevice, gl_StorageSemanticsBuffer,
                              gl_SemanticsRelaxed);
    return claimed < g.max_samples;
}

// True when the pixel traces rays this frame: into its cell (the paper), or its own (refinement frames).
bool pixel_traces(GPixel px, PixelCells pc, out uint first) {
    bool cell_takes = ray_target(px, pc, first);
    return cell_takes || (refine_frame() && px.t >= 0.0 && g.rays_per_pixel > 0u);
}

// Ray-tracing update, step 1, once the pixel's cells are known: clears the pixel's own-ray counts and queues it
// when it traces rays this frame (paper §6: cells full at max_samples stop receiving rays; in still-camera
// refinement frames every pixel traces). The queue is dense, so the update (ao_update.comp, dispatched
// indirectly) runs no idle lanes where most cells are full (navigation frames).
void queue_for_rays(uint index, GPixel px, PixelCells pc) {
    PixelRays none;
    none.traced = 0u;
    none.unoccluded = 0u;
    none.near_traced = 0u;
    none.near_open = 0u;
    none.open = 0u;
    PixelRaysRef(g.pixel_rays).v[index] = none;
    if (px.t < 0.0) return;
    uint first;
    bool traces = pixel_traces(px, pc, first);
    // Fractional budget (ours): outside refinement frames, a random subset of the pixels traces, a new one
    // each frame (the pixel index hashed with the frame index).
    bool picked = refine_frame() || g.trace_fraction >= 1.0
        || float(h_check(index ^ h_index(g.frame_index))) < g.trace_fraction * 4294967296.0;
    if (traces && picked) {
        uint slot = atomicAdd(StatsRef(g.stats).counters[STAT_RAY_QUEUE], 1u);
        UintRef(g.ray_queue).v[slot] = index;
    } else if (traces) {
        stat_add(STAT_UNPICKED_PIXELS, 1u);
    } else if (first < LOD_COUNT && g.rays_per_pixel > 0u) {
        stat_add(STAT_CAPPED_PIXELS, 1u);
    }
}

#endif
