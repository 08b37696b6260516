// The pixel's own rays pooled with its neighbours' on the same surface (ours): the rays traced this frame by
// the pixel and its 3x3 neighbours that lie on its plane, for a young map's additions (crate::additions). Needs
// common.glsl.
#ifndef HRTAO_POOL_GLSL
#define HRTAO_POOL_GLSL

// A neighbour is on the pixel's surface when its normal is within POOL_COS of the pixel's and it lies within
// POOL_PLANE steps (pixels, or the lattice's spacing) of the pixel's tangent plane.
const float POOL_COS = 0.95;
const float POOL_PLANE = 0.05;
const int POOL_RADIUS = 1;

// Whether G-buffer sample `pq` lies on the surface of pixel `px`; `tol` = POOL_PLANE * the pixel's world size.
bool same_surface(GPixel px, GPixel pq, float tol) {
    return pq.t >= 0.0 && dot(pq.normal, px.normal) >= POOL_COS && abs(dot(pq.position - px.position, px.normal)) <= tol;
}

// The rays traced this frame by the pixel and its 3x3 neighbours on its surface: (open within R, traced).
vec3 pooled_rays(uvec2 pix, GPixel px) {
    float tol = POOL_PLANE * step_world_size(px.t);
    vec3 sum = vec3(0.0);
    for (int dy = -POOL_RADIUS; dy <= POOL_RADIUS; ++dy) {
        for (int dx = -POOL_RADIUS; dx <= POOL_RADIUS; ++dx) {
            ivec2 q = neighbour(pix, ivec2(dx, dy));
            if (q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            uint qi = uint(q.y) * g.width + uint(q.x);
            PixelRays pr = PixelRaysRef(g.pixel_rays).v[qi];
            if (pr.near_traced == 0u) continue;
            GPixel pq = GBufferRef(g.gbuffer).px[qi];
            if (!same_surface(px, pq, tol)) continue;
            sum += vec3(float(pr.open), float(pr.near_open), float(pr.near_traced));
        }
    }
    return sum;
}

#endif
