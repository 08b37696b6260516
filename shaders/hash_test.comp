#version 460
// Evaluates the hash on test cases (push.xy = address of a HashTestCase array, push.z = count) so the
// CPU mirror in hash.rs can be compared bit for bit.
#include "common.glsl"
#include "hash.glsl"

layout(buffer_reference, scalar) buffer HashTestRef { HashTestCase v[]; };

void main() {
    uint i = gl_GlobalInvocationID.y * g.width + gl_GlobalInvocationID.x;
    if (gl_GlobalInvocationID.x >= g.width || i >= push.z) return;
    HashTestRef cases = HashTestRef(packUint2x32(push.xy));
    HashTestCase c = cases.v[i];
    int log2_s_min = g.log2_s_min;
    int lod = lod_of(c.s_w, log2_s_min) + int(c.lod_offset);
    CellKey key = cell_key(c.position, c.normal, lod, g.s_nd, g.normal_offset, c.scene_f, c.epoch, g.hash_capacity);
    cases.v[i].index = key.slot;
    cases.v[i].checksum = key.checksum;
    cases.v[i].lod = lod;
    cases.v[i].region = region_index(cell_coord(c.position, lod), lod, g.region_lod);
}
