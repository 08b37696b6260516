#version 460
// Ray-tracing update, step 1: queue the pixels that trace rays this frame (paper §6: cells full at max_samples
// stop receiving rays; in still-camera refinement frames every pixel traces). The queue is dense, so step 3
// runs no idle lanes where most cells are full (navigation frames). Clears every pixel's own-ray counts.
#include "common.glsl"
#include "ray_target.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    PixelRays none;
    none.traced = 0u;
    none.unoccluded = 0u;
    none.near_traced = 0u;
    none.near_open = 0u;
    PixelRaysRef(g.pixel_rays).v[index] = none;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    if (px.t < 0.0) return;
    uint first;
    bool traces = pixel_traces(px, PixelCellRef(g.pixel_cells).v[index], first);
    // Fractional budget (ours): outside refinement frames, a random subset of the pixels traces, a new one
    // each frame (the pixel index hashed with the frame index).
    bool picked = refine_frame() || g.trace_fraction >= 1.0
        || float(h_check(index ^ h_index(g.frame_index))) < g.trace_fraction * 4294967296.0;
    if (traces && picked) {
        uint slot = atomicAdd(StatsRef(g.stats).counters[STAT_RAY_QUEUE], 1u);
        UintRef(g.ray_queue).v[slot] = index;
    } else if (!traces && first < LOD_COUNT && g.rays_per_pixel > 0u) {
        stat_add(STAT_CAPPED_PIXELS, 1u);
    }
}
