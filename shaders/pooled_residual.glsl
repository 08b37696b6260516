// @correction order=1
// Pooled residual control variate (ours, `pooled_residual`, docs/algorithm.md), after the filter: a pixel whose
// cell is young corrects its filtered AO a by the rays traced this frame by it and its 3x3 neighbours on the same
// surface, r = open / traced - a, shrunk against the binomial noise v of those rays (Wiener: r^2 / (r^2 + λ v)).
// Cells of one or two pixels each hold the rays of a few faces' pixels, and the filter, which must cross cells to
// remove their noise, also crosses the faces; the pooled rays bring back what differs between them. After the
// filter, so it does not smooth the correction away. Runs in the first phase of the young map's corrections pass
// (corrections.comp), over its pixels (those that traced rays into young cells this frame, outside refinement
// frames). Needs common.glsl.
#ifndef HRTAO_POOLED_RESIDUAL_GLSL
#define HRTAO_POOLED_RESIDUAL_GLSL
#include "pool.glsl"
#include "correction.glsl"

// The λ of the Wiener weight r^2 / (r^2 + λ v).
const float POOLED_RESIDUAL_LAMBDA = 16.0;

// The AO `a` of pixel `c` corrected by the pooled rays.
float pooled_residual_phase1(CorrectedPixel c, float a) {
    vec3 pool = pooled_rays(c.pix, c.px);
    if (pool.z <= 0.0) return a;
    float n = pool.z;
    float r = pool.x / n - a;
    float p = clamp(a, 0.5 / (n + 1.0), 1.0 - 0.5 / (n + 1.0));
    float v = p * (1.0 - p) / n;
    float cell_var = p * (1.0 - p) / float(c.samples);
    float e = r * r + cell_var;
    return clamp(a + r * e / (e + POOLED_RESIDUAL_LAMBDA * v), 0.0, 1.0);
}

#endif
