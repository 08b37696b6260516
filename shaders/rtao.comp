#version 460
// Per-pixel RTAO, the brute-force baseline: rays_per_pixel cosine-weighted rays within ao_radius from each
// pixel's hit point, independent per pixel; frames are accumulated (ao_accum holds the running sum).
#include "common.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    FloatRef accum = FloatRef(g.ao_accum);
    float sum = g.accum_index == 0u ? 0.0 : accum.v[index];
    float value = 1.0;
    if (px.t >= 0.0 && g.rays_per_pixel > 0u) {
        vec3 origin = offset_ray(px.position, px.normal);
        vec2 shift = vec2(uint_to_unit(pcg_hash(index * 2u + 0x9e3779b9u)),
                          uint_to_unit(pcg_hash(index * 2u + 1u + 0x7f4a7c15u)));
        uint open = 0u;
        for (uint i = 0u; i < g.rays_per_pixel; ++i) {
            vec2 u = r2_point(g.accum_index * g.rays_per_pixel + i, shift);
            if (ray_unoccluded(origin, cosine_direction(px.normal, u), g.ao_radius)) open++;
        }
        value = float(open) / float(g.rays_per_pixel);
        atomicAdd(StatsRef(g.stats).counters[STAT_RAYS], g.rays_per_pixel);
    }
    sum += value;
    accum.v[index] = sum;
    FloatRef(g.ao).v[index] = sum / float(g.accum_index + 1u);
}
