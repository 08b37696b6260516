// Adaptive sampling of young cells (ours, `adaptive_rays`, docs/algorithm.md), in frames of a young map: the
// ray-tracing update's budget in three dispatches (push.x, `additions::adaptive_rays`) instead of one
// (PHASE_ALL): PHASE_FIRST traces a quarter of it, PHASE_WEIGH weighs every queued pixel by the noise its target
// cell still has, (p(1-p))^1.5 of the cell's rays so far, and sums the weights, PHASE_SECOND traces the other
// three quarters of the frame's budget, shared among the queued pixels in proportion to their weights (cells
// that came out open or closed take few rays, noisy ones many). Refinement frames trace the whole budget in the
// first dispatch. Needs common.glsl.
#ifndef HRTAO_ADAPTIVE_RAYS_GLSL
#define HRTAO_ADAPTIVE_RAYS_GLSL

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

// The rays the queued pixel `index` traces in dispatch `phase` of its budget g.rays_per_pixel: all of them in
// PHASE_ALL, and in PHASE_FIRST where the budget is not split (the pixel's own rays, or a budget of one ray);
// its part of the split otherwise (0 in PHASE_WEIGH, which weighs the pixel's target cell `cell` instead).
uint adaptive_budget(uint phase, bool own, uint index, uint cell) {
    uint first_part = g.rays_per_pixel >= 2u ? max(g.rays_per_pixel / 4u, 1u) : 0u;
    if (phase == PHASE_ALL) return g.rays_per_pixel;
    if (own || first_part == 0u) return phase == PHASE_FIRST ? g.rays_per_pixel : 0u;
    if (phase == PHASE_FIRST) return first_part;
    if (phase == PHASE_WEIGH) {
        float w = adapt_weight(CellRef(g.hash_cells), cell);
        FloatRef(g.filter_tmp).v[index] = w;   // scratch until the resolve: read back by the second part
        stat_add(STAT_ADAPT_WEIGHT, uint(w * ADAPT_WEIGHT_SCALE + 0.5));
        return 0u;
    }
    StatsRef stats = StatsRef(g.stats);
    float total = float(stats.counters[STAT_ADAPT_WEIGHT]) / ADAPT_WEIGHT_SCALE;
    float even = float(g.rays_per_pixel - first_part);
    float queued = float(stats.counters[STAT_RAY_QUEUE]);
    float share = total > 0.0 ? FloatRef(g.filter_tmp).v[index] * queued / total : 1.0;
    float want = even * min(share, ADAPT_MAX_SHARE);
    // Stochastic rounding: the expected total is the rest of the budget.
    float u = uint_to_unit(h_check(index ^ h_index(g.frame_index ^ 0x2545f491u)));
    return uint(floor(want + u));
}

#endif
