#version 460
// Contact detail's screen-space obscurance (ours, contact_detail > 0, while the map is young; see detail.comp):
// over every pixel, how much of the geometry around it rises above its tangent plane within R, into
// `obscurance`. It reads only the G-buffer, so it is dispatched right after primary visibility, beside the
// cell finder (one barrier for both).
#include "common.glsl"

// The obscurance's taps: the (2 r + 1)^2 - 1 pixels around the pixel (of the frame's lattice).
const int OBSCURANCE_RADIUS = 3;
// The cosine a neighbour must rise above the tangent plane by to count (a curved face's own tessellation
// does not).
const float OBSCURANCE_BIAS = 0.05;

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

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    FloatRef(g.obscurance).v[index] = px.t >= 0.0 ? obscurance(pix, px) : 0.0;
}
