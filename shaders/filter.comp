#version 460
// Adaptive final filtering (paper §5): an à-trous bilateral filter (Schied et al. 2017), iteration push.x of
// push.y, step 2^i pixels, reading one buffer and writing the other (ping-pong). Edge-stopping weights use the
// hash criteria: world distance relative to the cell size, and normal agreement at the s_nd resolution.
// The paper's filter (filter_sigma = 0): the kernel width follows the coarsest LOD used, so iteration i runs
// only where 2 * 2^i pixels fit in the footprint of the pixel's cell.
// Ours (filter_sigma > 0, docs/algorithm.md): the iterations that still leave visible noise run too, and a
// neighbour also stops the filter when its AO differs from the pixel's by more than filter_sigma standard
// deviations of the cell's binomial noise (SVGF's luminance edge-stopping with the variance the sample count
// gives), so young, noisy cells are smoothed over several cells while real AO gradients (contact shadows) stay.
// Pixels of full cells are left as they are, except in a still image's frames, where the cell estimate is the
// prior of the pixels' own rays and is filtered down to the noise of the final image's own rays
// (`still_prior_frame`). Which iterations a pixel takes is its plan (filter_plan.glsl).
// Sky light (ours, sky.glsl): the pixels' resolved transfer vectors are filtered with the same taps and weights,
// in their own ping-pong slots.
#include "common.glsl"
#include "hash_map.glsl"
#include "filter_plan.glsl"

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);
// Guided filter (ours): the world scale of the position weight in steps of the iteration (the taps reach 2
// steps), and the plane weight's tolerance in units of the iteration's reach (2 steps, at least the cell).
const float GUIDED_REACH = 4.0;
const float GUIDED_PLANE = 2.0;

// Guided (ours): the stop of the edge-stopping weight exp(-|value - center| stop) for a pixel whose value
// `center` is a fraction of the n rays of its cell (AO: open rays; sky light: escaped rays).
float guided_stop(float center, float n, float cell, float pixel_size, int step) {
    float p = clamp(center, 0.5 / (n + 1.0), 1.0 - 0.5 / (n + 1.0));
    float footprint = cell / max(pixel_size, 1e-30);
    float cells_spanned = 4.0 * float(step) / max(footprint, 1.0);
    float variance = p * (1.0 - p) / n / max(cells_spanned, 1.0);
    // A still image's prior (ours): differences within the noise the final image keeps from its own rays
    // (S_f = still_samples of them at the weight S_f / (k + S_f), composite.comp) are noise the final image
    // will not show; smoothing them keeps the refinement's first frames as smooth.
    if (still_prior_frame()) {
        float final_rays = max(g.still_samples, 1.0);
        float final_weight = final_rays / (g.prior_rays + final_rays);
        variance = max(variance, p * (1.0 - p) * final_weight * final_weight / final_rays);
    }
    return 1.0 / (g.filter_sigma * sqrt(2.0 * variance));
}

void main() {
    // Dispatched over the pixels whose plan takes an iteration (resolve.comp queues them); the others hold
    // their final value in both buffers already.
    uint q;
    if (!queue_entry(StatsRef(g.stats).counters[STAT_FILTER_QUEUE], q)) return;
    uint index = UintRef(g.filter_queue).v[q];
    uvec2 pix = uvec2(index % g.width, index / g.width);
    uint iteration = push.x;
    uint iterations = push.y;
    bool src_is_tmp = ((iterations - iteration) & 1u) == 1u;
    FloatRef src = FloatRef(src_is_tmp ? g.filter_tmp : g.ao);
    FloatRef dst = FloatRef(src_is_tmp ? g.ao : g.filter_tmp);
    // A pixel's plan (resolve.comp, filter_plan.glsl) ends after `done` iterations. The iteration after it
    // copies the value into the other buffer; from then on both hold it, and later iterations have nothing to
    // do for the pixel.
    uint plan = UintRef(g.filter_plan).v[index];
    uint done = plan_iterations(plan);
    if (iteration > done) return;
    float center = src.v[index];
    bool sky = sky_on() && SKY_FILTER;
    SkyPixelRef sky_px = SkyPixelRef(g.sky_pixels);
    uint sky_src = src_is_tmp ? SKY_PONG : SKY_RESOLVED;
    uint sky_dst = src_is_tmp ? SKY_RESOLVED : SKY_PONG;
    if (iteration == done) {
        dst.v[index] = center;
        if (sky) {
            for (uint i = 0u; i < SKY_COEFFS; ++i) {
                sky_px.v[index * SKY_PIXEL_FLOATS + sky_dst + i] = sky_px.v[index * SKY_PIXEL_FLOATS + sky_src + i];
            }
        }
        return;
    }
    GBufferRef gb = GBufferRef(g.gbuffer);
    GPixel px = gb.px[index];
    uint used = UintRef(g.lod_used).v[index];
    // World size of the cell the AO came from, and of one (internal) pixel at this distance.
    int lod = pixel_lod(px.t) + int(used);
    float cell = exp2(float(lod));
    // A step between taps: a pixel, or the spacing of the frame's lattice (slices), except with full taps.
    bool full_taps = filter_full_taps();
    float pixel_size = filter_step_size(px.t);
    int step = 1 << iteration;
    bool guided = g.filter_sigma > 0.0;
    // World scale of the position weights: the cell, or in the guided filter the reach of this iteration.
    float scale = guided ? max(cell, 2.0 * float(step) * pixel_size) : cell;
    // Guided, first frames (ours): the position weight reaches over twice the iteration's taps and the plane
    // weight admits parallel faces within 2 scales (otherwise a quarter), so a face of a few pixels borrows the
    // rays of its neighbours on nearby parallel planes where their AO agrees within the noise (san_francisco one
    // frame 0.0262 -> 0.0258, duplex 0.0093 -> 0.0083; docs/algorithm.md). Only in a young map's frames that are
    // not still refinement (the first frame from an empty map, after an edit): still frames and navigation
    // frames filter as before.
    bool wide = guided && (g.flags & FLAG_YOUNG_MAP) != 0u && !refine_frame();
    float pos_scale = wide ? max(cell, GUIDED_REACH * float(step) * pixel_size) : scale;
    float plane_scale = (wide ? GUIDED_PLANE : 0.25) * scale;
    // Guided: the noise of the pixel's value, p(1-p)/n for the n rays of its cell (p kept off 0 and 1 so an
    // open or closed cell still admits its neighbours' noise). The pixels of one cell share its noise, so the
    // averaging only lowers it once the kernel (4 steps wide) spans more than the cell's footprint: from there
    // it halves per doubling of the kernel.
    float n = float(max(plan_samples(plan), 1u));
    float stop = guided ? guided_stop(center, n, cell, pixel_size, step) : 0.0;
    // Sky light: the taps are weighed by the pixels' escaped fraction (the transfer's band 0 over an open
    // surface's), as the AO's by the AO, with that fraction's own binomial noise: the sky varies where the AO
    // within R does not (a face open within R, shadowed from afar).
    float sky_center = sky ? sky_escaped(sky_px.v[index * SKY_PIXEL_FLOATS + sky_src]) : 0.0;
    float sky_stop = sky && guided ? guided_stop(sky_center, n, cell, pixel_size, step) : 0.0;
    float sum = 0.0;
    float wsum = 0.0;
    float sky_sum[SKY_COEFFS];
    for (uint i = 0u; i < SKY_COEFFS; ++i) sky_sum[i] = 0.0;
    float sky_wsum = 0.0;
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
            ivec2 q = full_taps ? ivec2(pix) + ivec2(dx, dy) * step : neighbour(pix, ivec2(dx, dy) * step);
            if (q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            uint qi = uint(q.y) * g.width + uint(q.x);
            // A pixel of another slice contributes what it resolved when last drawn in this still image (none
            // yet in the first round's later slices: the tap is skipped).
            bool prior = full_taps && !in_slice(uvec2(q));
            SlicePrior sp = SlicePrior(src.v[qi], g.frame_index);
            if (prior) {
                sp = SlicePriorRef(g.slice_prior).v[qi];
                if (g.frame_index - sp.frame > g.frame_index - g.still_start_frame || !(sp.ao >= 0.0 && sp.ao <= 1.0)) {
                    continue;
                }
            }
            float value = sp.ao;
            FilterGuide guide = GuideRef(g.filter_guide).v[qi];
            if (guide.normal == GUIDE_NONE) continue;
            // A prior drawn before a local edit that changed geometry within its AO reach is stale (the
            // pixel sees the edit only when its slice is drawn again): no ghost of a removed part.
            if (prior && edited_within(guide.position, g.ao_radius + cell, g.frame_index - sp.frame)) continue;
            vec3 q_normal = unpack_normal(guide.normal);
            float k = KERNEL[abs(dx)] * KERNEL[abs(dy)];
            vec3 delta = guide.position - px.position;
            float w_pos = exp(-dot(delta, delta) / (pos_scale * pos_scale));
            float w_plane = exp(-abs(dot(delta, px.normal)) / plane_scale);
            float w_n = pow(max(dot(q_normal, px.normal), 0.0), 2.0 * g.s_nd);
            float w_ao = guided ? exp(-abs(value - center) * stop) : 1.0;
            float w_geometry = k * w_pos * w_plane * w_n;
            float w = w_geometry * w_ao;
            sum += w * value;
            wsum += w;
            // The sky's taps: the pixels drawn this frame (another slice's pixel keeps no transfer aside).
            if (sky && !prior) {
                uint at = qi * SKY_PIXEL_FLOATS + sky_src;
                float w_sky = w_geometry * (guided ? exp(-abs(sky_escaped(sky_px.v[at]) - sky_center) * sky_stop) : 1.0);
                for (uint i = 0u; i < SKY_COEFFS; ++i) sky_sum[i] += w_sky * sky_px.v[at + i];
                sky_wsum += w_sky;
            }
        }
    }
    dst.v[index] = wsum > 0.0 ? sum / wsum : center;
    if (sky) {
        uint at = index * SKY_PIXEL_FLOATS;
        for (uint i = 0u; i < SKY_COEFFS; ++i) {
            sky_px.v[at + sky_dst + i] = sky_wsum > 0.0 ? sky_sum[i] / sky_wsum : sky_px.v[at + sky_src + i];
        }
    }
}
