#version 460
// A young map's corrections (ours, docs/algorithm.md), after the filter, over the pixels that traced rays into
// their cells this frame (the ray queue), outside refinement frames, each in its own file: the pooled residual
// (pooled_residual.glsl) and the contact detail (contact_detail.glsl). push.x is the phase, push.y the
// corrections on (bit 0 the pooled residual, bit 1 the contact detail: `additions::Correction`), push.zw the
// contact detail's buffer:
//   1: the pooled residual, in place in `ao`; then the contact detail's fit;
//   2: the contact detail's correction, in place in `ao` (a pixel writes only its own value).
#include "common.glsl"
#include "filter_plan.glsl"
#include "pool.glsl"
#include "pooled_residual.glsl"
#include "contact_detail.glsl"

void main() {
    uint phase = push.x;
    bool residual = (push.y & 1u) != 0u;
    bool contact = (push.y & 2u) != 0u;
    if (refine_frame()) return;
    uint q;
    if (!queue_entry(StatsRef(g.stats).counters[STAT_RAY_QUEUE], q)) return;
    uint index = UintRef(g.ray_queue).v[q];
    if (index >= g.width * g.height) return;
    uint samples = plan_samples(UintRef(g.filter_plan).v[index]);
    if (samples == 0u || samples >= g.max_samples) return;   // no AO, or a full cell
    GPixel px = GBufferRef(g.gbuffer).px[index];
    if (px.t < 0.0) return;
    uvec2 pix = uvec2(index % g.width, index / g.width);
    FloatRef ao = FloatRef(g.ao);
    if (phase == 1u) {
        if (residual) ao.v[index] = pooled_residual_ao(pix, px, samples, ao.v[index]);
        if (contact) contact_detail_fit(index, pix, px, ao.v[index]);
    } else if (contact) {
        ao.v[index] = contact_detail_correct(pix, px, ao.v[index]);
    }
}
