#version 460
// Per-pixel RTAO, the brute-force baseline: rays_per_pixel cosine-weighted rays within ao_radius from each
// pixel's hit point, independent per pixel (its own R2 sequence continued over the still frames). The counts
// go to the pixel's PixelRays; composite.comp accumulates them over frames.
// One dispatch traces one chunk of the pass (dispatch_plan.rs, so that none trips a GPU watchdog): rays
// [push.y & 0xffff, + push.y >> 16) of every pixel (0xffff: to the end) of push.w rows from row push.z. The chunk
// with the first ray writes PixelRays, later ones add to it: the counts are those of one dispatch.
#define HRTAO_TRACES
#include "common.glsl"

void main() {
    uint first = push.y & 0xffffu;
    uint count = push.y >> 16;
    uint end = count == 0xffffu ? g.rays_per_pixel : min(first + count, g.rays_per_pixel);
    // Groups round the band up to whole work groups: the threads past its push.w rows are the next band's.
    if (THREAD_ID.y >= push.w) return;
    uvec2 pix = (THREAD_ID.xy + uvec2(0u, push.z)) * lattice() + uvec2(g.lattice_x, g.lattice_y);
    if (pix.x >= g.width || pix.y >= g.height) return;
    uint index = pix.y * g.width + pix.x;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    PixelRays pr;
    pr.traced = 0u;
    pr.unoccluded = 0u;
    pr.near_traced = 0u;
    pr.near_open = 0u;
    if (first > 0u) {
        if (px.t < 0.0 || first >= end) return;
        pr = PixelRaysRef(g.pixel_rays).v[index];
    }
    if (px.t >= 0.0 && first < end) {
        vec3 origin = offset_ray(px.position, px.normal);
        uvec2 shift = pixel_shift(index);
        for (uint i = first; i < end; ++i) {
            vec2 u = r2_point(g.still_index * g.rays_per_pixel + i, shift);
            if (ray_unoccluded(origin, cosine_direction(px.normal, u), g.ao_radius)) pr.unoccluded++;
        }
        pr.traced += end - first;
        rays_add(RAYS_ALL, end - first);
    }
    PixelRaysRef(g.pixel_rays).v[index] = pr;
}
