#version 460
// Collaborative ray tracing (paper §3, §6), step 3, over the queued pixels (dispatched indirectly, 2-D groups).
// A pixel whose target cell still takes rays traces up to `rays_per_pixel` AO rays from its hit point, each
// taking the next index of the cell's QMC sequence (one R2 sequence per cell, scrambled by the cell's
// checksum), cosine-weighted around the pixel's normal. In still-camera refinement frames (ours) every pixel
// traces its own R2 sequence instead, continued across the still frames; its rays also count for its cells.
// Results go to the target cell (up to max_samples) and propagate to the coarser cells (§4, up to SAMPLE_CAP).
// Ours, each in its own file: the near-field control variate classifies the rays (near_field.glsl) and adaptive
// sampling splits the budget of a young map's frame in three dispatches (adaptive_rays.glsl). Other frames trace
// the paper's first-hit queries in one. Each of those dispatches may itself be cut into chunks so that none trips
// a GPU watchdog (dispatch_plan.rs): push.y carries the chunk's rays of each pixel's budget, [push.y & 0xffff,
// + push.y >> 16) (0xffff: to the end of the budget), and push.z, push.w the queue entries it takes (bands of
// rows of the queue where one ray for every pixel is over the bound). A chunk claims its own rays from the
// cell's sequence and adds its counts, so the chunks of a budget add up to the budget traced at once.
#define HRTAO_TRACES
#include "common.glsl"
#include "ray_target.glsl"
#include "near_field.glsl"
#include "adaptive_rays.glsl"

// Ray counts of one pixel for one cell: traced, open, open within the near radius.
void add_rays(CellRef cells, uint c, uvec3 rays) {
    atomicAdd(cells.v[c].samples, rays.x);
    atomicAdd(cells.v[c].unoccluded, rays.y);
    if (near_field_on()) {
        atomicAdd(cells.v[c].near_traced, rays.x);
        atomicAdd(cells.v[c].near_open, rays.z);
    }
}

// One AO ray of the pixel's, counted (open, open within r_near) in `all_rays` and, when it is one of the target
// cell's, in `cell_rays`.
uint trace_counted(vec3 origin, vec3 dir, bool cells_ray, inout uvec3 all_rays, inout uvec3 cell_rays) {
    uint e = trace_ao_ray(origin, dir);
    uvec2 counts = uvec2(e == RAY_OPEN ? 1u : 0u, e != RAY_NEAR_HIT ? 1u : 0u);
    all_rays.yz += counts;
    if (cells_ray) cell_rays.yz += counts;
    return e;
}

void main() {
    uint q;
    if (!queue_entry(StatsRef(g.stats).counters[STAT_RAY_QUEUE], q)) return;
    if (q < push.z || q - push.z >= push.w) return;   // another chunk's band of the queue
    uint index = UintRef(g.ray_queue).v[q];
    if (index >= g.width * g.height) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    PixelCells pc = PixelCellRef(g.pixel_cells).v[index];
    uint first;
    bool cell_takes = ray_target(px, pc, first);
    bool own = refine_frame();
    if (!cell_takes && !own) return;
    CellRef cells = CellRef(g.hash_cells);
    // This dispatch's share of the budget (adaptive_rays.glsl: all of it, or a part of its split), the same in
    // every chunk of the dispatch (PHASE_WEIGH, which counts the pixel's weight, runs as one chunk).
    uint budget = adaptive_budget(push.x, own, index, own ? INVALID_CELL : pc.cells[first]);
    // This chunk's rays of it: [ray0, ray_end).
    uint ray0 = push.y & 0xffffu;
    uint ray_count = push.y >> 16;
    uint ray_end = ray_count == 0xffffu ? budget : min(ray0 + ray_count, budget);
    if (ray0 >= ray_end) return;
    uint chunk = ray_end - ray0;
    // Rays claimed from the target cell's QMC sequence (a block of the chunk's rays, cut at max_samples).
    uint qmc0 = 0u;
    uint claimed = 0u;
    if (cell_takes) {
        qmc0 = atomicAdd(cells.v[pc.cells[first]].qmc_index, chunk);
        claimed = qmc0 < g.max_samples ? min(chunk, g.max_samples - qmc0) : 0u;
    }
    uint rays = own ? chunk : claimed;
    uvec2 shift;
    uint seq0;
    if (own) {
        shift = pixel_shift(index);
        seq0 = g.still_index * g.rays_per_pixel + ray0;   // own rays: the whole budget in one phase
    } else {
        uint check = stamp_checksum(cells.v[pc.cells[first]].stamp);
        shift = uvec2(h_check(check), h_index(check ^ 0x5bd1e995u));
        seq0 = qmc0;
    }
    vec3 origin = offset_ray(px.position, px.normal);
    uvec3 all_rays = uvec3(rays, 0u, 0u);   // traced, open, open within r_near
    uvec3 cell_rays = uvec3(claimed, 0u, 0u);   // the same among the first `claimed` rays (the target cell's)
    // Sky light (sky.glsl): the basis values of the rays that escape, of all rays and of the target cell's. Two
    // loops, so that with the sky off its sums are not live across each traced ray (a ray-tracing pipeline
    // keeps what is live across traceRayEXT in its stack).
    bool sky = sky_on();
    float sky_all[SKY_COEFFS];
    float sky_cell[SKY_COEFFS];
    if (sky) {
        for (uint i = 0u; i < SKY_COEFFS; ++i) {
            sky_all[i] = 0.0;
            sky_cell[i] = 0.0;
        }
        for (uint r = 0u; r < rays; ++r) {
            vec3 dir = cosine_direction(px.normal, r2_point(seq0 + r, shift));
            if (trace_counted(origin, dir, r < claimed, all_rays, cell_rays) == RAY_OPEN && sky_escapes(origin, dir)) {
                float y[SKY_COEFFS];
                sky_basis(sky_frame(dir), y);
                for (uint i = 0u; i < SKY_COEFFS; ++i) {
                    sky_all[i] += y[i];
                    if (r < claimed) sky_cell[i] += y[i];
                }
            }
        }
    } else {
        for (uint r = 0u; r < rays; ++r) {
            trace_counted(origin, cosine_direction(px.normal, r2_point(seq0 + r, shift)), r < claimed, all_rays, cell_rays);
        }
    }
    if (rays == 0u) return;
    if (sky) {
        // Nothing non-finite enters the pixel's or the cells' sums.
        sky_finite(sky_all);
        sky_finite(sky_cell);
    }
    rays_add(RAYS_ALL, rays);
    // Cleared by the cell finder (queue_for_rays) each frame; the parts of a split budget (adaptive phases,
    // chunks) add up.
    if ((g.flags & FLAG_YOUNG_MAP) != 0u) {
        // This frame's rays of the pixel, for a young map's additions (near_field.glsl, corrections.comp),
        // which run only then.
        PixelRaysRef(g.pixel_rays).v[index].near_traced += rays;
        PixelRaysRef(g.pixel_rays).v[index].near_open += all_rays.z;
        PixelRaysRef(g.pixel_rays).v[index].open += all_rays.y;
    }
    if (own) {
        rays_add(RAYS_REFINE, rays);
        // The budget's first chunk sets the pixel's own rays of the frame, later chunks add theirs.
        PixelRays pr = PixelRaysRef(g.pixel_rays).v[index];
        PixelRaysRef(g.pixel_rays).v[index].traced = (ray0 == 0u ? 0u : pr.traced) + rays;
        PixelRaysRef(g.pixel_rays).v[index].unoccluded = (ray0 == 0u ? 0u : pr.unoccluded) + all_rays.y;
    }
    if (sky) {
        // Sky light: every ray the pixel traced this frame, its own or its cell's, is a sample of its own
        // transfer (the composite weighs them against the cell estimate). The first chunk of the frame sets
        // them, later chunks and phases add theirs.
        SkyPixelRef own_sky = SkyPixelRef(g.sky_pixels);
        uint base = index * SKY_PIXEL_FLOATS;
        bool fresh = floatBitsToUint(own_sky.v[base + SKY_OWN_FRAME]) != g.frame_index + 1u;
        for (uint i = 0u; i < SKY_COEFFS; ++i) {
            own_sky.v[base + SKY_OWN + i] = (fresh ? 0.0 : own_sky.v[base + SKY_OWN + i]) + sky_all[i];
        }
        own_sky.v[base + SKY_OWN_RAYS] = (fresh ? 0.0 : own_sky.v[base + SKY_OWN_RAYS]) + float(rays);
        own_sky.v[base + SKY_OWN_FRAME] = uintBitsToFloat(g.frame_index + 1u);
    }
    if (first >= LOD_COUNT) return;
    // The target cell takes the rays it granted; bottom-up propagation (§4): every coarser level takes all of
    // them until it holds SAMPLE_CAP.
    int lod = pixel_lod(px.t);
    if (claimed > 0u) {
        add_rays(cells, pc.cells[first], cell_rays);
        if (sky) sky_cell_add(pc.cells[first], sky_cell);
        rays_add(RAYS_CELL, claimed);
    }
    for (uint l = first + 1u; l < LOD_COUNT; ++l) {
        uint c = pc.cells[l];
        if (c == INVALID_CELL || !slot_in_bounds(c)) continue;
        // Atomic: other pixels add to the same coarse cell in this dispatch.
        uint samples = atomicLoad(cells.v[c].samples, gl_ScopeDevice, gl_StorageSemanticsBuffer, gl_SemanticsRelaxed);
        if (samples < SAMPLE_CAP) {
            add_rays(cells, c, all_rays);
            if (sky) sky_cell_add(c, sky_all);
        }
    }
}
