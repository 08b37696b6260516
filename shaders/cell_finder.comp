#version 460
// Cell finder (paper §4, Fig. 3): for each pixel, the hash cell at the target s_wd (level 0) or one of the
// LOD_COUNT - 1 successively coarser sizes (x2, x4, x8), found or inserted in the persistent world-space map.
// One dispatch per level, push.x = level, coarsest first: under overload the coarse cells, shared by many
// pixels, get the free slots, and pixels whose fine cells fail fall back to them (§4) instead of losing AO.
#include "common.glsl"
#include "hash_map.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    uint level = push.x;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    PixelCellRef cells = PixelCellRef(g.pixel_cells);
    if (level == LOD_COUNT - 1u) {
        PixelCells pc;
        pc.cells = uvec4(INVALID_CELL);
        cells.v[index] = pc;
    }
    if (px.t < 0.0) return;
    // A failed coarser level means the table is full here: finer cells would fail too.
    if (level < LOD_COUNT - 1u && cells.v[index].cells[level + 1u] == INVALID_CELL) return;
    int lod = pixel_lod(px.t);
    int l = lod + int(level);
    CellKey key = region_cell_key(cell_coord(px.position, l), l, normal_coord(px.normal, g.s_nd));
    cells.v[index].cells[level] = find_or_insert(key);
}
