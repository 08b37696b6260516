#version 460
// Per-pixel AO (paper §4): the finest of the pixel's cells holding at least `min_samples`, else the next
// coarser one (trading noise for spatial resolution); the LOD used is kept for the filter and debug views.
// At that LOD the value is reconstructed by trilinear interpolation of the 8 cells around the pixel (cells
// absent or empty drop out and the weights renormalise), so the cell grid does not show as blocks and the
// AO is centred on the pixel rather than on its cell.
// Ours (near_field.glsl): the near-field control variate corrects the cell estimate with the pixel's own rays.
// Sky light (ours, sky.glsl): the transfer is interpolated with the same weights; where those cells hold few rays
// it comes from coarser ones, carrying the pixel's detail within R by its AO (`sky_coarser`).
// Writes into the buffer the filter's ping-pong starts from, and queues the pixels the filter runs on
// (filter_plan.glsl, `store_resolved`).
#include "common.glsl"
#include "hash_map.glsl"
#include "filter_plan.glsl"
#include "pool.glsl"
#include "near_field.glsl"
#include "queue_args.glsl"

// Trilinear interpolation at level `lod` of the 8 cells around `position` (cells absent or empty drop out):
// (sum of w AO, the near-open fraction times sum of w, sum of w, the rays the weighted mean is worth:
// (sum w)^2 / sum w^2/s). The near-open fraction is interpolated over the cells that classified rays (-1 when
// none did). With the sky light, `sky` the sum of w times each cell's transfer (sky.glsl).
vec4 interpolate(vec3 position, int lod, ivec3 nq, inout float sky[SKY_COEFFS]) {
    CellRef cells = CellRef(g.hash_cells);
    vec3 u = ldexp(position, ivec3(-lod)) - 0.5;
    vec3 base = floor(u);
    vec3 f = u - base;
    ivec3 b = ivec3(clamp(base, vec3(-2147483520.0), vec3(2147483520.0)));
    float sum = 0.0;
    float near_sum = 0.0;
    float wsum = 0.0;
    float w2s = 0.0;
    float near_w = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        ivec3 o = ivec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        vec3 wv = mix(1.0 - f, f, vec3(o));
        float w = wv.x * wv.y * wv.z;
        if (w <= 0.0) continue;
        uint c = find_cell(region_cell_key(b + o, lod, nq));
        if (c == INVALID_CELL) continue;
        uint s = cells.v[c].samples;
        if (s == 0u) continue;
        w *= min(1.0, float(s) / float(max(g.min_samples, 1u)));
        float ao = float(cells.v[c].unoccluded) / float(s);
        sum += w * ao;
        uint near_traced = cells.v[c].near_traced;
        if (near_traced > 0u) {
            near_sum += w * (float(cells.v[c].near_open) / float(near_traced));
            near_w += w;
        }
        wsum += w;
        w2s += w * w / float(s);
        if (sky_on()) {
            for (uint i = 0u; i < SKY_COEFFS; ++i) sky[i] += w * sky_cell_mean(c, i, float(s));
        }
    }
    float near = near_w > 0.0 ? near_sum / near_w * wsum : -1.0;
    return vec4(sum, near, wsum, w2s > 0.0 ? wsum * wsum / w2s : 0.0);
}

// Sky light (ours): a young map's transfer from coarser cells. What escapes past R is blocked, if at all, by
// geometry beyond R: it varies over distances of the order of R, not of the pixel's cell, so a coarser cell
// estimates it as well, from more rays (a cell of the next level holds about 4 times the rays). What varies
// within a cell is the occlusion within R, which the pixel's AO has at its own level (near-field corrected):
// with V = V_R V_far, the pixel's transfer is taken as the coarser cell's times the AO's ratio, pixel over that
// cell, the escaped fraction staying below the pixel's AO as the cells' stays below theirs. Goes up to
// SKY_COARSER_LEVELS levels while the estimate is worth fewer than SKY_SAMPLES_FACTOR x min_samples rays: the
// sky's escaped fraction sits near 1/2 where the AO within R sits near 1, so the same noise needs more rays.
// Full cells keep their own level: the converged transfer is the pixel's own. Rod's first frame at 160x90,
// against Cycles: uniform 0.0298 -> 0.0240, the lobe 0.0308 -> 0.0267 (cycloidal unchanged, 0.026).
const int SKY_COARSER_LEVELS = 2;
const float SKY_SAMPLES_FACTOR = 4.0;

void sky_coarser(vec3 position, int lod, ivec3 nq, float ao, float rays, inout float sky[SKY_COEFFS]) {
    float enough = SKY_SAMPLES_FACTOR * float(g.min_samples);
    float coarse[SKY_COEFFS];
    for (int up = 1; up <= SKY_COARSER_LEVELS && rays < enough; ++up) {
        for (uint i = 0u; i < SKY_COEFFS; ++i) coarse[i] = 0.0;
        vec4 c = interpolate(position, lod + up, nq, coarse);
        if (c.z <= 0.0) return;
        float ratio = clamp(ao, 0.0, 1.0) / max(c.x / c.z, 1e-3);
        for (uint i = 0u; i < SKY_COEFFS; ++i) sky[i] = coarse[i] / c.z * ratio;
        rays = c.w;
    }
}

void resolve_pixel() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    float ao = 1.0;
    uint used = LOD_COUNT;
    uint iterations = (g.flags & FLAG_FILTER) != 0u ? g.filter_iterations : 0u;
    uint plan = 0u;
    // Sky light: the pixel's cell transfer (open where it has no cell, as its AO is 1).
    float sky[SKY_COEFFS];
    for (uint i = 0u; i < SKY_COEFFS; ++i) sky[i] = 0.0;
    bool sky_resolved = false;
    if (px.t >= 0.0) {
        PixelCells pc = PixelCellRef(g.pixel_cells).v[index];
        CellRef cells = CellRef(g.hash_cells);
        uint best = LOD_COUNT;
        uint best_samples = 0u;
        // A cell without rays never counts as holding enough (min_samples = 0 would pick it and show it open).
        uint enough = max(g.min_samples, 1u);
        for (uint l = 0u; l < LOD_COUNT; ++l) {
            uint c = pc.cells[l];
            if (c == INVALID_CELL || !slot_in_bounds(c)) continue;
            uint s = cells.v[c].samples;
            if (s >= enough) {
                best = l;
                break;
            }
            if (s > best_samples) {
                best = l;
                best_samples = s;
            }
        }
        if (best < LOD_COUNT && cells.v[pc.cells[best]].samples > 0u) {
            used = best;
            int lod = pixel_lod(px.t) + int(best);
            ivec3 nq = normal_coord(px.normal, g.s_nd, g.normal_offset);
            vec4 fine = interpolate(px.position, lod, nq, sky);
            float sum = fine.x;
            float near_sum = fine.y;
            float wsum = fine.z;
            uint own = pc.cells[best];
            float own_samples = float(cells.v[own].samples);
            ao = wsum > 0.0 ? sum / wsum : float(cells.v[own].unoccluded) / own_samples;
            if (sky_on()) {
                for (uint i = 0u; i < SKY_COEFFS; ++i) {
                    sky[i] = wsum > 0.0 ? sky[i] / wsum : sky_cell_mean(own, i, own_samples);
                }
                sky_resolved = true;
            }
            // Near-field control variate (ours, near_field.glsl): the pixel's own rays against its cells'.
            PixelRays pr = PixelRaysRef(g.pixel_rays).v[index];
            uint own_near = cells.v[own].near_traced;
            bool cells_near = wsum > 0.0 ? near_sum >= 0.0 : own_near > 0u;
            float cell_near = !cells_near ? 0.0
                : wsum > 0.0 ? near_sum / wsum : float(cells.v[own].near_open) / float(own_near);
            ao += near_field_correction(pix, px, pr, cells_near, cell_near);
            if (sky_on()) sky_coarser(px.position, lod, nq, ao, fine.w, sky);
            float footprint = exp2(float(lod)) / max(filter_step_size(px.t), 1e-30);   // cell width in steps
            uint own_rays = uint(own_samples);
            plan = make_plan(planned_iterations(footprint, own_rays, iterations), own_rays);
        }
    }
    if (sky_on()) {
        if (!sky_resolved && px.t >= 0.0) sky_open_transfer(unpack_normal(px.shading), sky);
        sky_finite(sky);
        // Where the filter starts, as store_resolved does the AO: a pixel that takes no iteration into both.
        bool odd = SKY_FILTER && (iterations & 1u) == 1u;
        SkyPixelRef pixels = SkyPixelRef(g.sky_pixels);
        uint start = index * SKY_PIXEL_FLOATS + (odd ? SKY_PONG : SKY_RESOLVED);
        uint other = index * SKY_PIXEL_FLOATS + (odd ? SKY_RESOLVED : SKY_PONG);
        bool both = SKY_FILTER && plan_iterations(plan) == 0u && iterations > 0u;
        for (uint i = 0u; i < SKY_COEFFS; ++i) {
            pixels.v[start + i] = sky[i];
            if (both) pixels.v[other + i] = sky[i];
        }
    }
    GuideRef(g.filter_guide).v[index] = make_guide(px, used < LOD_COUNT);
    store_resolved(index, plan, clamp(finite_or_count(ao, 1.0), 0.0, 1.0), iterations);
    if (filter_full_taps()) {
        SlicePriorRef(g.slice_prior).v[index] = SlicePrior(clamp(ao, 0.0, 1.0), g.frame_index);
    }
    UintRef(g.lod_used).v[index] = used;
}

void main() {
    resolve_pixel();
    // The filter's dispatch size over the pixels queued for it.
    write_queue_args(STAT_FILTER_QUEUE, FILTER_ARGS_OFFSET);
}
