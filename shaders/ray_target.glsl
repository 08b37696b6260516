// Which pixels trace AO rays this frame, and into which cell (paper §3, §6). Shared by ao_select.comp and
// ao_update.comp.
#ifndef HRTAO_RAY_TARGET_GLSL
#define HRTAO_RAY_TARGET_GLSL
#include "hash_map.glsl"

// Still-camera refinement frame (ours): every pixel traces its own rays.
bool refine_frame() { return (g.flags & FLAG_REFINE) != 0u && g.still_index > 0u; }

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
    return CellRef(g.hash_cells).v[target].qmc_index < g.max_samples;
}

// True when the pixel traces rays this frame: into its cell (the paper), or its own (refinement frames).
bool pixel_traces(GPixel px, PixelCells pc, out uint first) {
    bool cell_takes = ray_target(px, pc, first);
    return cell_takes || (refine_frame() && px.t >= 0.0 && g.rays_per_pixel > 0u);
}

#endif
