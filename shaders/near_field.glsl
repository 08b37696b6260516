// Near-field control variate (ours, `near_field`, docs/algorithm.md), in frames of a young map
// (FLAG_NEAR_FIELD). The ray-tracing update classifies each ray: does it hit within the near radius
// r_n = NEAR_FRACTION R? Cells count those rays and the ones open within r_n, and the pixel keeps its own counts
// (ao_update.comp). The resolve then corrects the cell estimate by the pixel's own near-open fraction minus its
// cells' (`near_field_correction`), which restores the contact shadows a cell averages away. Other frames trace
// the paper's first-hit queries. Needs common.glsl.
#ifndef HRTAO_NEAR_FIELD_GLSL
#define HRTAO_NEAR_FIELD_GLSL
#include "pool.glsl"

// The weight β of the pixel's own near-open fraction minus its cells'.
const float NEAR_WEIGHT = 1.0;
// The near radius r_n as a fraction of R (smaller radii make the near-open fraction curve within a cell where
// the AO does not, which biases the correction).
const float NEAR_FRACTION = 0.5;

// `trace_ao_ray` results: the ray hits within the near radius, hits beyond it (within R), or hits nothing.
const uint RAY_NEAR_HIT = 0u;
const uint RAY_FAR_HIT = 1u;
const uint RAY_OPEN = 2u;

// Whether this frame classifies its rays (the near field is on and the map is young).
bool near_field_on() {
    return (g.flags & FLAG_NEAR_FIELD) != 0u;
}

#ifdef HRTAO_TRACES
// As ray_unoccluded, telling also whether the ray hits within r_near: the paper's first-hit query over
// [0, tmax]; only when the hit it found lies beyond r_near, a second first-hit query over [0, r_near]. An open
// ray and a ray whose first found hit is near cost what they cost the paper. (On lavapipe a closest-hit query
// instead cost rod's navigation frames 2.6x the paper's ray update, a near-then-far pair of first-hit queries
// 1.6x, with the same rays.)
uint ray_escape(vec3 p, vec3 dir, float r_near, float tmax) {
    float tmin = 0.0;
    if (!section_clip(p, dir, tmin, tmax)) return RAY_OPEN;
    float t = segment_first_hit(p, dir, tmin, tmax);
    if (t < 0.0) return RAY_OPEN;
    if (t <= r_near) return RAY_NEAR_HIT;
    return segment_first_hit(p, dir, tmin, min(r_near, tmax)) >= 0.0 ? RAY_NEAR_HIT : RAY_FAR_HIT;
}

// One AO ray of length R from `origin`: classified when the near field is on, else the paper's query (a hit
// then counts as near).
uint trace_ao_ray(vec3 origin, vec3 dir) {
    if (near_field_on()) return ray_escape(origin, dir, NEAR_FRACTION * g.ao_radius, g.ao_radius);
    return ray_unoccluded(origin, dir, g.ao_radius) ? RAY_OPEN : RAY_NEAR_HIT;
}
#endif

// The correction of pixel `pix`'s cell estimate: its own near-open fraction minus its cells' (`cell_near`, the
// interpolated near-open fraction) moves the estimate toward the pixel's contact shadow. The residual r is shrunk
// against the binomial noise v of the pixel's few rays (Wiener: P/(P+v)), with the power P of the contact
// estimated from the residual r_q of the rays pooled over the pixel's same-surface 3x3 neighbours (pool.glsl),
// or from r r_q where the pixel and its neighbours agree: a contact shadow spans several pixels, a pixel whose
// few rays were unlucky does not (P = r^2, the pixel's own, speckled the first frames of a view). Not in
// still-camera refinement frames: there the pixel's own rays enter the composite directly, and a correction
// from each frame's few rays would only add flicker. 0 when the pixel or its cells classified no rays.
float near_field_correction(uvec2 pix, GPixel px, PixelRays pr, bool cells_near, float cell_near) {
    if (!near_field_on() || pr.near_traced == 0u || !cells_near || refine_frame()) return 0.0;
    float n = float(pr.near_traced);
    float r = float(pr.near_open) / n - cell_near;
    float v = max(cell_near * (1.0 - cell_near), 0.5 / n) / n;
    vec3 pool = pooled_rays(pix, px);   // holds the pixel's own rays: pool.z >= n
    float rq = pool.y / pool.z - cell_near;
    float power = max(rq * rq, r * rq);
    return NEAR_WEIGHT * r * power / (power + v);
}

#endif
