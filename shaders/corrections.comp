#version 460
// A young map's corrections (ours, docs/algorithm.md, `crate::additions`), after the filter, over the pixels that
// traced rays into their cells this frame (the ray queue), outside refinement frames. Each correction is a shader
// file of its own, marked `@correction` (correction.glsl); build.rs generates `corrections.glsl` from them: their
// includes and `apply_corrections`, which applies in their order those of a phase that are on. push.x is the
// phase, push.y the corrections on (their masks, `additions::generated`), push.zw what a correction's buffer
// needs (`additions::record_corrections`). A pixel reads and writes only its own AO.
#include "common.glsl"
#include "filter_plan.glsl"
#include "correction.glsl"
#include "corrections.glsl"

void main() {
    if (refine_frame()) return;
    uint q;
    if (!queue_entry(StatsRef(g.stats).counters[STAT_RAY_QUEUE], q)) return;
    uint index = UintRef(g.ray_queue).v[q];
    if (index >= g.width * g.height) return;
    uint samples = plan_samples(UintRef(g.filter_plan).v[index]);
    if (samples == 0u || samples >= g.max_samples) return;   // no AO, or a full cell
    GPixel px = GBufferRef(g.gbuffer).px[index];
    if (px.t < 0.0) return;
    CorrectedPixel c = CorrectedPixel(index, uvec2(index % g.width, index / g.width), px, samples);
    FloatRef ao = FloatRef(g.ao);
    float a = ao.v[index];
    float corrected = apply_corrections(push.x, push.y, c, a);
    if (corrected != a) ao.v[index] = corrected;
}
