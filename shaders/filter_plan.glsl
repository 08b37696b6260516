// A pixel's filter plan (written by resolve.comp, read by filter.comp and composite.comp): how many à-trous
// iterations it takes, and the rays of the cell its AO came from (for the guided filter's noise and the still
// refinement's prior). Deciding once per pixel keeps a skipped iteration to one read. Needs common.glsl.
#ifndef HRTAO_FILTER_PLAN_GLSL
#define HRTAO_FILTER_PLAN_GLSL

uint plan_iterations(uint plan) { return plan & ((1u << FILTER_PLAN_BITS) - 1u); }
uint plan_samples(uint plan) { return plan >> FILTER_PLAN_BITS; }

// The iterations of a pixel whose cell (`samples` rays, estimate `ao`) spans `footprint` pixels, out of
// `iterations`. The paper (§5): iteration i runs where 2 * 2^i pixels fit in the cell's footprint. Ours, the
// guided filter (filter_sigma > 0): a full cell (max_samples, §6) holds its final estimate and takes none; a
// cell of n rays also runs the iterations that bring its noise down to a full cell's (its binomial variance
// p(1-p)/n halves per iteration: log2(max_samples / n) of them), so young cells are smoothed over several
// cells. A navigation frame (`navigation_frame`: few young cells, scattered) takes the paper's iterations,
// full cells none, so it filters fewer pixels than the paper's filter. A still image's frames
// (`still_prior_frame`) take at least 2, full cells too (filter.comp).
uint planned_iterations(float footprint, uint samples, uint iterations) {
    uint paper = 0u;
    while (paper < iterations && float(2u << paper) <= footprint) paper++;
    if (g.filter_sigma <= 0.0) return paper;
    uint full = max(g.max_samples, 1u);
    // A still image's prior (ours): full cells too take at least 2 iterations, filtered to the noise of the
    // final image's own rays (filter.comp).
    bool prior = still_prior_frame();
    if (samples >= full && !prior) return 0u;
    if (navigation_frame() && !prior) return paper;
    uint noisy = 0u;
    while (noisy < iterations && (max(samples, 1u) << noisy) < full) noisy++;
    return max(max(paper, noisy), prior ? min(iterations, 2u) : 0u);
}

// The filter's guide of a pixel (FilterGuide): a pixel without AO (a miss, or no cell) stops every tap.
layout(buffer_reference, scalar) buffer GuideRef { FilterGuide v[]; };
// What each pixel resolved when last drawn (SlicePrior, `filter_full_taps`).
layout(buffer_reference, scalar) buffer SlicePriorRef { SlicePrior v[]; };

FilterGuide make_guide(GPixel px, bool has_ao) {
    FilterGuide guide;
    guide.position = px.position;
    guide.normal = has_ao ? pack_normal(px.normal) : GUIDE_NONE;
    return guide;
}

// Stores a pixel's resolved AO where the filter starts (the buffer iteration 0 reads, so that an even or odd
// count of `iterations` ends in `ao`) and its plan. A pixel that takes no iteration is final: it goes into both
// buffers, where the filter's taps find it at every iteration, and stays out of the filter's queue. The others
// are queued (STAT_FILTER_QUEUE): the filter runs densely over them, however scattered they are.
void store_resolved(uint index, uint plan, float ao, uint iterations) {
    UintRef(g.filter_plan).v[index] = plan;
    bool odd = (iterations & 1u) == 1u;
    FloatRef(odd ? g.filter_tmp : g.ao).v[index] = ao;
    if (plan_iterations(plan) == 0u) {
        if (iterations > 0u) FloatRef(odd ? g.ao : g.filter_tmp).v[index] = ao;
    } else {
        uint slot = atomicAdd(StatsRef(g.stats).counters[STAT_FILTER_QUEUE], 1u);
        UintRef(g.filter_queue).v[slot] = index;
    }
}

uint make_plan(uint iterations, uint samples) {
    return min(iterations, (1u << FILTER_PLAN_BITS) - 1u) | (min(samples, 0xffffffffu >> FILTER_PLAN_BITS) << FILTER_PLAN_BITS);
}

#endif
