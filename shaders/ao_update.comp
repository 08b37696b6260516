#version 460
// Collaborative ray tracing (paper §3, §6), step 3, over the queued pixels (dispatched indirectly): each traces
// up to `rays_per_pixel` AO rays from its hit point into its target cell. Every ray takes the next index of the
// cell's QMC sequence (one R2 sequence per cell, scrambled by the cell's checksum), cosine-weighted around the
// pixel's normal. Results go to the target cell and propagate to the coarser cells (§4).
#include "common.glsl"
#include "ray_target.glsl"

void main() {
    uint q = gl_WorkGroupID.x * (WORKGROUP_SIZE * WORKGROUP_SIZE) + gl_LocalInvocationIndex;
    if (q >= StatsRef(g.stats).counters[STAT_RAY_QUEUE]) return;
    uint index = UintRef(g.ray_queue).v[q];
    if (index >= g.width * g.height) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    PixelCells pc = PixelCellRef(g.pixel_cells).v[index];
    uint first;
    if (!ray_target(index, px, pc, first)) return;
    CellRef cells = CellRef(g.hash_cells);
    uint target = pc.cells[first];
    uint check = cells.v[target].checksum;
    vec2 shift = vec2(uint_to_unit(h_check(check)), uint_to_unit(h_index(check ^ 0x5bd1e995u)));
    vec3 origin = offset_ray(px.position, px.normal);
    uint traced = 0u;
    uint open = 0u;
    for (uint r = 0u; r < g.rays_per_pixel; ++r) {
        uint qi = atomicAdd(cells.v[target].qmc_index, 1u);
        if (qi >= g.max_samples) break;
        vec3 dir = cosine_direction(px.normal, r2_point(qi, shift));
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
