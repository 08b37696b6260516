#version 460
// Pooled residual control variate (ours, pooled_residual > 0, docs/algorithm.md), after the filter: a pixel whose
// cell is young corrects its filtered AO a by the rays traced this frame by it and its 3x3 neighbours on the same
// surface, r = open / traced - a, shrunk against the binomial noise v of those rays (Wiener: r^2 / (r^2 + λ v)).
// Cells of one or two pixels each hold the rays of a few faces' pixels, and the filter, which must cross cells to
// remove their noise, also crosses the faces; the pooled rays bring back what differs between them. After the
// filter, so it does not smooth the correction away. Pixels of full cells (settled navigation frames) and
// refinement frames are left as they are. Reads and writes `ao` in place (a pixel writes only its own value).
#include "common.glsl"
#include "filter_plan.glsl"

// A neighbour is on the pixel's surface when its normal is within POOL_COS of the pixel's and it lies within
// POOL_PLANE pixels of the pixel's tangent plane.
const float POOL_COS = 0.95;
const float POOL_PLANE = 0.05;
const int POOL_RADIUS = 1;

// The rays traced this frame by the pixel and its 3x3 neighbours on its surface: (open within R, traced).
vec2 pooled_rays(uvec2 pix, GPixel px) {
    float tol = POOL_PLANE * pixel_world_size(px.t);
    vec2 sum = vec2(0.0);
    for (int dy = -POOL_RADIUS; dy <= POOL_RADIUS; ++dy) {
        for (int dx = -POOL_RADIUS; dx <= POOL_RADIUS; ++dx) {
            ivec2 q = ivec2(pix) + ivec2(dx, dy);
            if (q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            uint qi = uint(q.y) * g.width + uint(q.x);
            PixelRays pr = PixelRaysRef(g.pixel_rays).v[qi];
            if (pr.near_traced == 0u) continue;
            GPixel pq = GBufferRef(g.gbuffer).px[qi];
            if (pq.t < 0.0 || dot(pq.normal, px.normal) < POOL_COS
                || abs(dot(pq.position - px.position, px.normal)) > tol) continue;
            sum += vec2(float(pr.open), float(pr.near_traced));
        }
    }
    return sum;
}

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    if ((g.flags & FLAG_REFINE) != 0u && g.still_index > 0u) return;
    uint plan = UintRef(g.filter_plan).v[index];
    uint samples = plan_samples(plan);
    if (samples == 0u || samples >= g.max_samples) return;   // no AO, or a full cell
    GPixel px = GBufferRef(g.gbuffer).px[index];
    if (px.t < 0.0) return;
    vec2 pool = pooled_rays(pix, px);
    if (pool.y <= 0.0) return;
    FloatRef ao = FloatRef(g.ao);
    float a = ao.v[index];
    float r = pool.x / pool.y - a;
    float p = clamp(a, 0.5 / (pool.y + 1.0), 1.0 - 0.5 / (pool.y + 1.0));
    float v = p * (1.0 - p) / pool.y;
    ao.v[index] = clamp(a + r * r * r / (r * r + g.pooled_residual * v), 0.0, 1.0);
}
