#version 460
// Pooled residual control variate (ours, pooled_residual > 0, docs/algorithm.md), after the filter: a pixel whose
// cell is young corrects its filtered AO a by the rays traced this frame by it and its 3x3 neighbours on the same
// surface, r = open / traced - a, shrunk against the binomial noise v of those rays (Wiener: r^2 / (r^2 + λ v)).
// Cells of one or two pixels each hold the rays of a few faces' pixels, and the filter, which must cross cells to
// remove their noise, also crosses the faces; the pooled rays bring back what differs between them. After the
// filter, so it does not smooth the correction away. Dispatched indirectly over the pixels that traced rays into
// their cells this frame (the ray queue, as ao_update.comp), only while the map is young (Renderer::young_map,
// which also has the ray update count each pixel's rays): pixels of full cells and navigation frames cost
// nothing; refinement frames are left as they are. Reads and writes `ao` in place (a pixel writes
// only its own value).
#include "common.glsl"
#include "filter_plan.glsl"
#include "pool.glsl"

void main() {
    if (refine_frame()) return;
    uint q;
    if (!queue_entry(StatsRef(g.stats).counters[STAT_RAY_QUEUE], q)) return;
    uint index = UintRef(g.ray_queue).v[q];
    if (index >= g.width * g.height) return;
    uvec2 pix = uvec2(index % g.width, index / g.width);
    uint plan = UintRef(g.filter_plan).v[index];
    uint samples = plan_samples(plan);
    if (samples == 0u || samples >= g.max_samples) return;   // no AO, or a full cell
    GPixel px = GBufferRef(g.gbuffer).px[index];
    if (px.t < 0.0) return;
    vec3 pool = pooled_rays(pix, px);
    if (pool.z <= 0.0) return;
    FloatRef ao = FloatRef(g.ao);
    float a = ao.v[index];
    float n = pool.z;
    float r = pool.x / n - a;
    float p = clamp(a, 0.5 / (n + 1.0), 1.0 - 0.5 / (n + 1.0));
    float v = p * (1.0 - p) / n;
    float cell_var = p * (1.0 - p) / float(samples);
    float e = r * r + cell_var;
    ao.v[index] = clamp(a + r * e / (e + g.pooled_residual * v), 0.0, 1.0);
}
