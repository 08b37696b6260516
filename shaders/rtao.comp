#version 460
// Per-pixel RTAO, the brute-force baseline: rays_per_pixel cosine-weighted rays within ao_radius from each
// pixel's hit point, independent per pixel (its own R2 sequence continued over the still frames). The counts
// go to the pixel's PixelRays; composite.comp accumulates them over frames.
#include "common.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    PixelRays pr;
    pr.traced = 0u;
    pr.unoccluded = 0u;
    pr.near_traced = 0u;
    pr.near_open = 0u;
    if (px.t >= 0.0 && g.rays_per_pixel > 0u) {
        vec3 origin = offset_ray(px.position, px.normal);
        uvec2 shift = pixel_shift(index);
        for (uint i = 0u; i < g.rays_per_pixel; ++i) {
            vec2 u = r2_point(g.still_index * g.rays_per_pixel + i, shift);
            if (ray_unoccluded(origin, cosine_direction(px.normal, u), g.ao_radius)) pr.unoccluded++;
        }
        pr.traced = g.rays_per_pixel;
        rays_add(RAYS_ALL, g.rays_per_pixel);
    }
    PixelRaysRef(g.pixel_rays).v[index] = pr;
}
