// @correction order=2
// Contact detail (ours, `contact_detail`, docs/algorithm.md), while the map is young. Cells and the filter average
// AO over several pixels, so contact shadows finer than them come out too light and the open faces beside them
// too dark. The G-buffer still holds that detail: a pixel's screen-space obscurance o (how much of the geometry
// around it rises above its tangent plane within R) minus the mean o of its surface's 3x3 neighbours is its
// detail d. The AO takes k d, where the gain k is fitted each frame by least squares to the rays the pixels
// traced, y - a = k d (y a pixel's open fraction, a its AO after the corrections before it), over every
// corrected pixel and weighted by their rays t: k = Σ t (y - a) d / Σ t d², shrunk by the Wiener weight
// k² / (k² + v) against its binomial noise v <= 1/4 / Σ t d², and never positive (more geometry around a pixel
// never opens it). The pixels' own rays enter a through its cells, but their noise is independent of d, so the
// fit is not biased.
//
// Three steps: `contact_detail.comp` writes every pixel's obscurance right after primary visibility (it reads
// only the G-buffer, so it shares the cell finder's barrier); after the filter, the young map's corrections
// pass (corrections.comp) sums the fit in its phase 1 (`contact_detail_phase1`, after the corrections of lower
// order) and corrects in its phase 2 (`contact_detail_phase2`). Needs common.glsl.
#ifndef HRTAO_CONTACT_DETAIL_GLSL
#define HRTAO_CONTACT_DETAIL_GLSL
#include "pool.glsl"
#include "correction.glsl"

// The obscurance's taps: the (2 r + 1)^2 - 1 pixels around the pixel (of the frame's lattice).
const int OBSCURANCE_RADIUS = 3;
// The cosine a neighbour must rise above the tangent plane by to count (a curved face's own tessellation
// does not).
const float OBSCURANCE_BIAS = 0.05;
// The weight of the fitted gain (1 = the fit).
const float CONTACT_DETAIL_GAIN = 1.0;
// Fixed point of the fit's sums.
const float DETAIL_SUM_SCALE = 1048576.0;

// Its buffer (`additions::contact_detail::Target`), whose address its passes get in push.zw: the fit's two sums
// over the pixels it corrects, Σ t (y - a) d and Σ t d² in 1/DETAIL_SUM_SCALE units (reset by the obscurance
// pass), then every pixel's obscurance.
layout(buffer_reference, scalar, buffer_reference_align = 8) buffer ContactDetailRef {
    int64_t sums[2];
    float obscurance[];
};

// How much of the geometry around pixel `pix` rises above its tangent plane within R.
float obscurance(uvec2 pix, GPixel px) {
    float sum = 0.0;
    for (int dy = -OBSCURANCE_RADIUS; dy <= OBSCURANCE_RADIUS; ++dy) {
        for (int dx = -OBSCURANCE_RADIUS; dx <= OBSCURANCE_RADIUS; ++dx) {
            ivec2 q = neighbour(pix, ivec2(dx, dy));
            if ((dx == 0 && dy == 0) || q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            GPixel pq = GBufferRef(g.gbuffer).px[uint(q.y) * g.width + uint(q.x)];
            if (pq.t < 0.0) continue;
            vec3 d = pq.position - px.position;
            float len = length(d);
            if (len <= 0.0) continue;
            sum += max(dot(px.normal, d) / len - OBSCURANCE_BIAS, 0.0) * max(1.0 - len / g.ao_radius, 0.0);
        }
    }
    int side = 2 * OBSCURANCE_RADIUS + 1;
    return sum / float(side * side - 1);
}

// The pixel's obscurance minus the mean of its surface's 3x3 neighbours' (itself included).
float detail(uvec2 pix, GPixel px) {
    ContactDetailRef cd = ContactDetailRef(packUint2x32(push.zw));
    float tol = POOL_PLANE * step_world_size(px.t);
    float sum = 0.0;
    float n = 0.0;
    for (int dy = -POOL_RADIUS; dy <= POOL_RADIUS; ++dy) {
        for (int dx = -POOL_RADIUS; dx <= POOL_RADIUS; ++dx) {
            ivec2 q = neighbour(pix, ivec2(dx, dy));
            if (q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            uint qi = uint(q.y) * g.width + uint(q.x);
            if (!same_surface(px, GBufferRef(g.gbuffer).px[qi], tol)) continue;
            sum += cd.obscurance[qi];
            n += 1.0;
        }
    }
    return cd.obscurance[pix.y * g.width + pix.x] - sum / max(n, 1.0);
}

// The fit's sums over pixel `c` (AO `a`, after the corrections before it): Σ t (y - a) d and Σ t d². Leaves `a`.
float contact_detail_phase1(CorrectedPixel c, float a) {
    PixelRays pr = PixelRaysRef(g.pixel_rays).v[c.index];
    if (pr.near_traced == 0u) return a;
    float d = detail(c.pix, c.px);
    float t = float(pr.near_traced);
    float y = float(pr.open) / t;
    ContactDetailRef cd = ContactDetailRef(packUint2x32(push.zw));
    atomicAdd(cd.sums[0], int64_t(t * (y - a) * d * DETAIL_SUM_SCALE));
    atomicAdd(cd.sums[1], int64_t(t * d * d * DETAIL_SUM_SCALE));
    return a;
}

// The AO `a` of pixel `c` darkened by the fitted gain times its detail.
float contact_detail_phase2(CorrectedPixel c, float a) {
    ContactDetailRef cd = ContactDetailRef(packUint2x32(push.zw));
    float dd = float(cd.sums[1]) / DETAIL_SUM_SCALE;
    if (dd <= 0.0) return a;
    float k = min(float(cd.sums[0]) / DETAIL_SUM_SCALE / dd, 0.0);
    k *= k * k / (k * k + 0.25 / dd);
    return clamp(a + CONTACT_DETAIL_GAIN * k * detail(c.pix, c.px), 0.0, 1.0);
}

#endif
