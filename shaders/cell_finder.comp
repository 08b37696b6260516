#version 460
// Cell finder (paper §4, Fig. 3): for each pixel, the hash cell at the target s_wd (level 0) and at the
// LOD_COUNT - 1 successively coarser sizes (x2, x4, x8), found or inserted in the persistent world-space map.
// Levels push.x down to push.y (coarsest first): all of them in one pass, one dispatch per level while the table
// is crowded (TableLoad::cell_levels), so that the coarse cells, shared by many pixels, get the free slots first.
// A failed level means the table is full here: finer cells would fail too, and the pixel falls back to the
// coarser cells it has (§4) instead of losing AO. The dispatch that ends at level 0 also
// queues the pixel for the ray-tracing update (ray_target.glsl `queue_for_rays`).
#include "common.glsl"
#include "hash_map.glsl"
#include "ray_target.glsl"
#include "queue_args.glsl"

void find_cells() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    uint top = push.x;
    uint bottom = push.y;
    PixelCellRef cells = PixelCellRef(g.pixel_cells);
    PixelCells pc;
    pc.cells = uvec4(INVALID_CELL);
    if (top < LOD_COUNT - 1u) pc = cells.v[index];
    GPixel px = GBufferRef(g.gbuffer).px[index];
    if (px.t >= 0.0 && (top == LOD_COUNT - 1u || pc.cells[top + 1u] != INVALID_CELL)) {
        int lod = pixel_lod(px.t);
        ivec3 nq = normal_coord(px.normal, g.s_nd, g.normal_offset);
        for (int level = int(top); level >= int(bottom); --level) {
            int l = lod + level;
            uint c = find_or_insert(region_cell_key(cell_coord(px.position, l), l, nq));
            pc.cells[level] = c;
            if (c == INVALID_CELL) break;
        }
    }
    cells.v[index] = pc;
    if (bottom == 0u) queue_for_rays(index, px, pc);
}

void main() {
    find_cells();
    // The last level's dispatch queued the pixels: the ray-tracing update's dispatch size.
    if (push.y == 0u) write_queue_args(STAT_RAY_QUEUE, RAY_ARGS_OFFSET);
}
