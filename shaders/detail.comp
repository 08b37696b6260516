#version 460
// The corrections of a young map's pixels (ours, docs/algorithm.md), after the filter, over the pixels that traced
// rays into their cells this frame (the ray queue), outside refinement frames: the pooled residual
// (residual.glsl) and the contact detail. push.x is the phase, push.y the corrections on (bit 0 the pooled
// residual, bit 1 the contact detail):
//   1: the pooled residual, in place in `ao`; then the contact detail's sums into STAT_DETAIL_SUMS;
//   2: the contact detail's correction, in place in `ao` (a pixel writes only its own value).
//
// Contact detail (contact_detail > 0). Cells and the filter average AO over several pixels, so contact shadows
// finer than them come out too light and the open faces beside them too dark. The G-buffer still holds that
// detail: a pixel's screen-space obscurance o (how much of the geometry around it rises above its tangent plane
// within R) minus the mean o of its surface's 3x3 neighbours is its detail d. The AO takes k d, where the gain k
// is fitted each frame by least squares to the rays the pixels traced, y - a = k d (y a pixel's open fraction, a
// its AO after the pooled residual), over every corrected pixel and weighted by their rays t:
// k = Σ t (y - a) d / Σ t d², shrunk by the Wiener weight k² / (k² + v) against its binomial noise
// v <= 1/4 / Σ t d², and never positive (more geometry around a pixel never opens it). The pixels' own rays enter
// a through its cells, but their noise is independent of d, so the fit is not biased. obscurance.comp,
// dispatched after primary visibility, wrote every pixel's obscurance.
#include "common.glsl"
#include "filter_plan.glsl"
#include "pool.glsl"
#include "residual.glsl"

layout(buffer_reference, scalar, buffer_reference_align = 8) buffer DetailSumsRef { int64_t v[2]; };

// The pixel's obscurance minus the mean of its surface's 3x3 neighbours' (itself included).
float detail(uvec2 pix, GPixel px) {
    FloatRef o = FloatRef(g.obscurance);
    float tol = POOL_PLANE * step_world_size(px.t);
    float sum = 0.0;
    float n = 0.0;
    for (int dy = -POOL_RADIUS; dy <= POOL_RADIUS; ++dy) {
        for (int dx = -POOL_RADIUS; dx <= POOL_RADIUS; ++dx) {
            ivec2 q = neighbour(pix, ivec2(dx, dy));
            if (q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            uint qi = uint(q.y) * g.width + uint(q.x);
            if (!same_surface(px, GBufferRef(g.gbuffer).px[qi], tol)) continue;
            sum += o.v[qi];
            n += 1.0;
        }
    }
    return o.v[pix.y * g.width + pix.x] - sum / max(n, 1.0);
}

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
    if (phase == 1u && residual) {
        ao.v[index] = pooled_residual_ao(pix, px, samples, ao.v[index]);
    }
    if (!contact) return;
    float d = detail(pix, px);
    DetailSumsRef sums = DetailSumsRef(g.stats + uint64_t(4u * STAT_DETAIL_SUMS));
    float scale = float(DETAIL_SUM_SCALE);
    if (phase == 1u) {
        PixelRays pr = PixelRaysRef(g.pixel_rays).v[index];
        if (pr.near_traced == 0u) return;
        float t = float(pr.near_traced);
        float y = float(pr.open) / t;
        atomicAdd(sums.v[0], int64_t(t * (y - ao.v[index]) * d * scale));
        atomicAdd(sums.v[1], int64_t(t * d * d * scale));
        return;
    }
    float dd = float(sums.v[1]) / scale;
    if (dd <= 0.0) return;
    float k = min(float(sums.v[0]) / scale / dd, 0.0);
    k *= k * k / (k * k + 0.25 / dd);
    ao.v[index] = clamp(ao.v[index] + g.contact_detail * k * d, 0.0, 1.0);
}
