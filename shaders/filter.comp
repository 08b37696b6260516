#version 460
// Adaptive final filtering (paper §5): an à-trous bilateral filter (Schied et al. 2017), iteration push.x of
// push.y, step 2^i pixels, reading one buffer and writing the other (ping-pong). Edge-stopping weights use the
// hash criteria: world distance relative to the cell size, and normal agreement at the s_nd resolution.
// The paper's filter (filter_sigma = 0): the kernel width follows the coarsest LOD used, so iteration i runs
// only where 2 * 2^i pixels fit in the footprint of the pixel's cell.
// Ours (filter_sigma > 0, docs/algorithm.md): every iteration runs, and a neighbour also stops the filter when
// its AO differs from the pixel's by more than filter_sigma standard deviations of the cell's binomial noise
// (SVGF's luminance edge-stopping with the variance the sample count gives), so young, noisy cells are
// smoothed over several cells while real AO gradients (contact shadows) stay. Pixels of full cells are left
// as they are.
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
    bool guided = g.filter_sigma > 0.0;
    if (!guided && float(2 * step) > footprint) {
        dst.v[index] = center;
        return;
    }
    // World scale of the position weights: the cell, or in the guided filter the reach of this iteration.
    float scale = guided ? max(cell, 2.0 * float(step) * pixel_size) : cell;
    // Guided: the noise of the pixel's value, p(1-p)/n for the n rays of its cell (p kept off 0 and 1 so an
    // open or closed cell still admits its neighbours' noise), halved per iteration as the filter averages.
    float stop = 0.0;
    if (guided) {
        uint c = PixelCellRef(g.pixel_cells).v[index].cells[used];
        uint samples = c == INVALID_CELL || !slot_in_bounds(c) ? 1u : max(CellRef(g.hash_cells).v[c].samples, 1u);
        // A full cell (max_samples, §6) holds its final estimate: nothing left to smooth, and settled
        // navigation frames, whose cells are mostly full, cost what the paper's filter costs.
        if (samples >= max(g.max_samples, 1u)) {
            dst.v[index] = center;
            return;
        }
        float n = float(samples);
        float p = clamp(center, 0.5 / (n + 1.0), 1.0 - 0.5 / (n + 1.0));
        float variance = p * (1.0 - p) / n * exp2(-float(iteration));
        stop = 1.0 / (g.filter_sigma * sqrt(2.0 * variance));
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
            float w_pos = exp(-dot(delta, delta) / (scale * scale));
            float w_plane = exp(-abs(dot(delta, px.normal)) / (0.25 * scale));
            float w_n = pow(max(dot(qp.normal, px.normal), 0.0), 2.0 * g.s_nd);
            float w_ao = guided ? exp(-abs(src.v[qi] - center) * stop) : 1.0;
            float w = k * w_pos * w_plane * w_n * w_ao;
            sum += w * src.v[qi];
            wsum += w;
        }
    }
    dst.v[index] = wsum > 0.0 ? sum / wsum : center;
}
