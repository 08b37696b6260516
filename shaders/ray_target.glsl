// The cell a pixel's AO rays go to (paper §3, §6): the finest of its cells that exists (inserts may fail under
// overload), unless that cell already holds max_samples. Shared by ao_select.comp and ao_update.comp.
#ifndef HRTAO_RAY_TARGET_GLSL
#define HRTAO_RAY_TARGET_GLSL
#include "hash_map.glsl"

// Returns the LOD level of the target in `first` and true when the pixel traces rays this frame.
bool ray_target(uint index, GPixel px, PixelCells pc, out uint first) {
    first = LOD_COUNT;
    if (px.t < 0.0 || g.rays_per_pixel == 0u) return false;
    first = 0u;
    while (first < LOD_COUNT && pc.cells[first] == INVALID_CELL) first++;
    if (first == LOD_COUNT) return false;
    uint target = pc.cells[first];
    if (!slot_in_bounds(target)) return false;
    return CellRef(g.hash_cells).v[target].samples < g.max_samples;
}

#endif
