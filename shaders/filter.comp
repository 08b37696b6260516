#version 460
// Adaptive final filtering (paper §5): an à-trous bilateral filter (Schied et al. 2017), iteration push.x of
// push.y, step 2^i pixels, reading one buffer and writing the other (ping-pong). The kernel width follows the
// coarsest LOD used: a pixel whose AO came from a cell of size s is smoothed over about that size on screen,
// so iteration i runs only where 2 * 2^i pixels fit in that footprint. Edge-stopping weights use the hash
// criteria: world distance relative to the cell size, and normal agreement at the s_nd resolution.
#include "common.glsl"
#include "hash_map.glsl"

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    uint iteration = push.x;
    uint iterations = push.y;
    bool src_is_tmp = ((iterations - iteration) & 1u) == 1u;
    FloatRef src = FloatRef(src_is_tmp ? g.filter_tmp : g.ao);
    FloatRef dst = FloatRef(src_is_tmp ? g.ao : g.filter_tmp);
    GBufferRef gb = GBufferRef(g.gbuffer);
    GPixel px = gb.px[index];
    float center = src.v[index];
    uint used = UintRef(g.lod_used).v[index];
    if (px.t < 0.0 || used >= LOD_COUNT) {
        dst.v[index] = center;
        return;
    }
    // World size of the cell the AO came from, and of one pixel at this distance.
    int lod = pixel_lod(px.t) + int(used);
    float cell = exp2(float(lod));
    // World width of one (internal) pixel at this distance.
    float pixel_size = pixel_world_size(px.t);
    float footprint = cell / max(pixel_size, 1e-30);   // cell width in pixels
    int step = 1 << iteration;
    if (float(2 * step) > footprint) {
        dst.v[index] = center;
        return;
    }
    float sum = 0.0;
    float wsum = 0.0;
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
            ivec2 q = ivec2(pix) + ivec2(dx, dy) * step;
            if (q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            uint qi = uint(q.y) * g.width + uint(q.x);
            GPixel qp = gb.px[qi];
            if (qp.t < 0.0 || UintRef(g.lod_used).v[qi] >= LOD_COUNT) continue;
            float k = KERNEL[abs(dx)] * KERNEL[abs(dy)];
            vec3 delta = qp.position - px.position;
            float w_pos = exp(-dot(delta, delta) / (cell * cell));
            float w_plane = exp(-abs(dot(delta, px.normal)) / (0.25 * cell));
            float w_n = pow(max(dot(qp.normal, px.normal), 0.0), 2.0 * g.s_nd);
            float w = k * w_pos * w_plane * w_n;
            sum += w * src.v[qi];
            wsum += w;
        }
    }
    dst.v[index] = wsum > 0.0 ? sum / wsum : center;
}
