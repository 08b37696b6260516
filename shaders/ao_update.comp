#version 460
// Collaborative ray tracing (paper §3, §6): each pixel traces up to `rays_per_pixel` AO rays from its hit
// point into its target cell, unless the cell already holds `max_samples`. Every ray takes the next index of
// the cell's QMC sequence (one R2 sequence per cell, scrambled by the cell's checksum), cosine-weighted
// around the pixel's normal. Results go to the target cell and propagate to the coarser cells (§4).
#include "common.glsl"
#include "hash_map.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    if (px.t < 0.0 || g.rays_per_pixel == 0u) return;
    PixelCells pc = PixelCellRef(g.pixel_cells).v[index];
    // The target is the finest cell that exists (inserts may fail under overload).
    uint first = 0u;
    while (first < LOD_COUNT && pc.cells[first] == INVALID_CELL) first++;
    if (first == LOD_COUNT) return;
    CellRef cells = CellRef(g.hash_cells);
    uint target = pc.cells[first];
    if (!slot_in_bounds(target)) return;
    if (cells.v[target].samples >= g.max_samples) {
        stat_add(STAT_CAPPED_PIXELS, 1u);
        return;
    }
    uint check = cells.v[target].checksum;
    vec2 shift = vec2(uint_to_unit(h_check(check)), uint_to_unit(h_index(check ^ 0x5bd1e995u)));
    vec3 origin = offset_ray(px.position, px.normal);
    uint traced = 0u;
    uint open = 0u;
    for (uint r = 0u; r < g.rays_per_pixel; ++r) {
        uint q = atomicAdd(cells.v[target].qmc_index, 1u);
        if (q >= g.max_samples) break;
        vec3 dir = cosine_direction(px.normal, r2_point(q, shift));
        if (ray_unoccluded(origin, dir, g.ao_radius)) open++;
        traced++;
    }
    if (traced == 0u) return;
    stat_add(STAT_RAYS, traced);
    // Bottom-up propagation: the target and every coarser level receive the rays.
    for (uint l = first; l < LOD_COUNT; ++l) {
        uint c = pc.cells[l];
        if (c == INVALID_CELL || !slot_in_bounds(c)) continue;
        atomicAdd(cells.v[c].samples, traced);
        atomicAdd(cells.v[c].unoccluded, open);
    }
}
