#version 460
// Collaborative ray tracing (paper §3, §6), step 3, over the queued pixels (dispatched indirectly, 2-D groups).
// A pixel whose target cell still takes rays traces up to `rays_per_pixel` AO rays from its hit point, each
// taking the next index of the cell's QMC sequence (one R2 sequence per cell, scrambled by the cell's
// checksum), cosine-weighted around the pixel's normal. In still-camera refinement frames (ours) every pixel
// traces its own R2 sequence instead, continued across the still frames; its rays also count for its cells.
// Results go to the target cell (up to max_samples) and propagate to the coarser cells (§4, up to SAMPLE_CAP).
// Near-field control variate (ours, FLAG_NEAR_FIELD: near_weight > 0 in frames of a young map): each ray also
// tells whether it hit within the near radius r_n; cells count those rays and the ones open within r_n, and
// the pixel keeps its own counts for resolve.comp. Other frames trace the paper's first-hit queries.
// Adaptive sampling of young cells (ours, adaptive_rays, docs/algorithm.md): push.x = 0 traces the whole budget
// in one dispatch; otherwise three dispatches split it: 1 traces a quarter of it, 2 weighs every queued pixel by
// the noise its target cell still has, (p(1-p))^1.5 of the cell's rays so far, and sums the weights, 3 traces
// the other three quarters of the frame's budget, shared among the queued pixels in proportion to their
// weights (cells that came out open or closed take few rays, noisy ones many). Refinement frames trace the
// whole budget in the first dispatch.
#include "common.glsl"
#include "ray_target.glsl"

const uint PHASE_ALL = 0u;
const uint PHASE_FIRST = 1u;
const uint PHASE_WEIGH = 2u;
const uint PHASE_SECOND = 3u;
// Fixed point of the weights summed in STAT_ADAPT_WEIGHT (a weight is at most 0.25^1.5 = 1/8: no u32 overflow
// below 2^25 queued pixels).
const float ADAPT_WEIGHT_SCALE = 1024.0;
// A pixel takes at most this many times its even share of the second part.
const float ADAPT_MAX_SHARE = 4.0;
const float ADAPT_EXP = 1.5;

// The weight of a pixel for the second part: (p(1-p))^ADAPT_EXP of its target cell's rays so far, with p kept
// off 0 and 1 (a cell that came out all open may still hide a rare occluder). Measured on the five shared
// scenes (docs/algorithm.md): the exponent 1/3 that minimises the summed standard deviation of independent
// pixels gains least; cells are shared and their noise is what the filter cannot remove, and 1.5 gains most.
float adapt_weight(CellRef cells, uint c) {
    // Atomic loads: the counters are atomics (no pass writes them during this phase, but a plain read of an
    // atomically updated word is a data race in the memory model).
    uint samples = atomicLoad(cells.v[c].samples, gl_ScopeDevice, gl_StorageSemanticsBuffer, gl_SemanticsRelaxed);
    uint open = atomicLoad(cells.v[c].unoccluded, gl_ScopeDevice, gl_StorageSemanticsBuffer, gl_SemanticsRelaxed);
    float n = float(max(samples, 1u));
    float p = clamp(float(open) / n, 0.5 / (n + 1.0), 1.0 - 0.5 / (n + 1.0));
    return pow(p * (1.0 - p), ADAPT_EXP);
}

// Ray counts of one pixel for one cell: traced, open, open within the near radius.
void add_rays(CellRef cells, uint c, uvec3 rays) {
    atomicAdd(cells.v[c].samples, rays.x);
    atomicAdd(cells.v[c].unoccluded, rays.y);
    if ((g.flags & FLAG_NEAR_FIELD) != 0u) {
        atomicAdd(cells.v[c].near_traced, rays.x);
        atomicAdd(cells.v[c].near_open, rays.z);
    }
}

void main() {
    uint q;
    if (!queue_entry(StatsRef(g.stats).counters[STAT_RAY_QUEUE], q)) return;
    uint index = UintRef(g.ray_queue).v[q];
    if (index >= g.width * g.height) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    PixelCells pc = PixelCellRef(g.pixel_cells).v[index];
    uint first;
    bool cell_takes = ray_target(px, pc, first);
    bool own = refine_frame();
    if (!cell_takes && !own) return;
    CellRef cells = CellRef(g.hash_cells);
    // This dispatch's share of the budget (adaptive sampling splits it in two parts, see above).
    uint phase = push.x;
    uint first_part = g.rays_per_pixel >= 2u ? max(g.rays_per_pixel / 4u, 1u) : 0u;
    bool split = phase != PHASE_ALL && !own && first_part > 0u;
    uint budget = g.rays_per_pixel;
    if (phase != PHASE_ALL && !split) {
        if (phase != PHASE_FIRST) return;   // the whole budget went in the first dispatch
    } else if (phase == PHASE_FIRST) {
        budget = first_part;
    } else if (phase == PHASE_WEIGH) {
        float w = adapt_weight(cells, pc.cells[first]);
        FloatRef(g.filter_tmp).v[index] = w;   // scratch until the resolve: read back by the second part
        stat_add(STAT_ADAPT_WEIGHT, uint(w * ADAPT_WEIGHT_SCALE + 0.5));
        return;
    } else if (phase == PHASE_SECOND) {
        StatsRef stats = StatsRef(g.stats);
        float total = float(stats.counters[STAT_ADAPT_WEIGHT]) / ADAPT_WEIGHT_SCALE;
        float even = float(g.rays_per_pixel - first_part);
        float queued = float(stats.counters[STAT_RAY_QUEUE]);
        float share = total > 0.0 ? FloatRef(g.filter_tmp).v[index] * queued / total : 1.0;
        float want = even * min(share, ADAPT_MAX_SHARE);
        // Stochastic rounding: the expected total is the rest of the budget.
        float u = uint_to_unit(h_check(index ^ h_index(g.frame_index ^ 0x2545f491u)));
        budget = uint(floor(want + u));
        if (budget == 0u) return;
    }
    // Rays claimed from the target cell's QMC sequence (a block of `budget`, cut at max_samples).
    uint qmc0 = 0u;
    uint claimed = 0u;
    if (cell_takes) {
        qmc0 = atomicAdd(cells.v[pc.cells[first]].qmc_index, budget);
        claimed = qmc0 < g.max_samples ? min(budget, g.max_samples - qmc0) : 0u;
    }
    uint rays = own ? budget : claimed;
    uvec2 shift;
    uint seq0;
    if (own) {
        shift = pixel_shift(index);
        seq0 = g.still_index * g.rays_per_pixel;   // own rays: the whole budget in one dispatch
    } else {
        uint check = stamp_checksum(cells.v[pc.cells[first]].stamp);
        shift = uvec2(h_check(check), h_index(check ^ 0x5bd1e995u));
        seq0 = qmc0;
    }
    vec3 origin = offset_ray(px.position, px.normal);
    float r_near = g.near_fraction * g.ao_radius;
    bool near_field = (g.flags & FLAG_NEAR_FIELD) != 0u;
    uvec3 all_rays = uvec3(rays, 0u, 0u);   // traced, open, open within r_near
    uvec3 cell_rays = uvec3(claimed, 0u, 0u);   // the same among the first `claimed` rays (the target cell's)
    for (uint r = 0u; r < rays; ++r) {
        vec3 dir = cosine_direction(px.normal, r2_point(seq0 + r, shift));
        uint e = near_field ? ray_escape(origin, dir, r_near, g.ao_radius)
                                     : (ray_unoccluded(origin, dir, g.ao_radius) ? RAY_OPEN : RAY_NEAR_HIT);
        uvec2 counts = uvec2(e == RAY_OPEN ? 1u : 0u, e != RAY_NEAR_HIT ? 1u : 0u);
        all_rays.yz += counts;
        if (r < claimed) cell_rays.yz += counts;
    }
    if (rays == 0u) return;
    rays_add(RAYS_ALL, rays);
    // Cleared by the cell finder (queue_for_rays) each frame; the two halves of a split budget add up.
    if ((g.flags & FLAG_YOUNG_MAP) != 0u) {
        // This frame's rays of the pixel, for the near-field control variate (resolve.comp, when classified)
        // and the pooled residual (residual.glsl); both run only while the map is young.
        PixelRaysRef(g.pixel_rays).v[index].near_traced += rays;
        PixelRaysRef(g.pixel_rays).v[index].near_open += all_rays.z;
        PixelRaysRef(g.pixel_rays).v[index].open += all_rays.y;
    }
    if (own) {
        rays_add(RAYS_REFINE, rays);
        PixelRaysRef(g.pixel_rays).v[index].traced = rays;
        PixelRaysRef(g.pixel_rays).v[index].unoccluded = all_rays.y;
    }
    if (first >= LOD_COUNT) return;
    // The target cell takes the rays it granted; bottom-up propagation (§4): every coarser level takes all of
    // them until it holds SAMPLE_CAP.
    int lod = pixel_lod(px.t);
    if (claimed > 0u) {
        add_rays(cells, pc.cells[first], cell_rays);
        rays_add(RAYS_CELL, claimed);
    }
    for (uint l = first + 1u; l < LOD_COUNT; ++l) {
        uint c = pc.cells[l];
        if (c == INVALID_CELL || !slot_in_bounds(c)) continue;
        // Atomic: other pixels add to the same coarse cell in this dispatch.
        uint samples = atomicLoad(cells.v[c].samples, gl_ScopeDevice, gl_StorageSemanticsBuffer, gl_SemanticsRelaxed);
        if (samples < SAMPLE_CAP) add_rays(cells, c, all_rays);
    }
}
