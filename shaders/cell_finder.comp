#version 460
// Cell finder (paper §4, Fig. 3): for each pixel, the hash cells at the target s_wd and the LOD_COUNT - 1
// successively coarser sizes (x2, x4, x8), found or inserted in the persistent world-space map.
#include "common.glsl"
#include "hash_map.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    PixelCells pc;
    pc.cells = uvec4(INVALID_CELL);
    pc.lod = 0u;
    pc._pad = uvec3(0u);
    if (px.t >= 0.0) {
        int lod = pixel_lod(px.t);
        pc.lod = uint(lod - g.log2_s_min);
        for (uint l = 0u; l < LOD_COUNT; ++l) {
            CellKey key = cell_key(px.position, px.normal, lod + int(l), g.s_nd, g.scene_frame, g.hash_capacity);
            pc.cells[l] = find_or_insert(key);
        }
    }
    PixelCellRef(g.pixel_cells).v[index] = pc;
}
