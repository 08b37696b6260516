// The world-space hash of HRTAO (paper §1-2, eq. 1-6). Mirrored bit-for-bit by crates/hrtao-core/src/hash.rs.
//
// h_index and h_check are two independent 32-bit integer hashes: the first gives the cell's slot in the map,
// the second a checksum telling apart keys that share a slot. Positions are quantised exactly: the cell size
// s_wd = 2^(lod) with lod = floor(log2(s_w)) read from the float's exponent, and s_min rounded to a power of
// two, so p / s_wd is a power-of-two scaling (ldexp) with no rounding on the CPU or the GPU.
#ifndef HRTAO_HASH_GLSL
#define HRTAO_HASH_GLSL

// "lowbias32" (C. Wellons, hash-prospector): bias 0.17, a full-avalanche 32-bit permutation.
uint h_index(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// PCG output permutation (O'Neill; "RXS-M-XS" as used by Jarzynski and Olano 2020): independent of h_index.
uint h_check(uint x) {
    uint state = x * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// eq. (3) on the integer log scale: the LOD of a target feature size s_w is floor(log2(s_w)), clamped to
// the smallest level log2(s_min); cell size s_wd = 2^lod.
int lod_of(float s_w, int log2_s_min) {
    if (!(s_w > 0.0) || isinf(s_w)) return log2_s_min;   // also catches NaN
    int e;
    frexp(s_w, e);           // s_w = m 2^e with m in [0.5, 1): floor(log2(s_w)) = e - 1
    return max(e - 1, log2_s_min);
}

// Integer cell coordinate of p at LOD `lod` (floor(p / s_wd)), clamped to the int range.
ivec3 cell_coord(vec3 p, int lod) {
    vec3 q = floor(ldexp(p, ivec3(-lod)));
    q = clamp(q, vec3(-2147483520.0), vec3(2147483520.0));
    return ivec3(q);
}

// eq. (5)'s normal quantisation, floor(n s_nd + offset). The paper's floor(n s_nd) (offset 0, its mode) puts
// bin edges exactly on axis-aligned normals, the most common normals in CAD, and bins centred on the integers
// (offset 1/2) put them at n = ±1/2, where 30°/60° chamfers and hexagon faces sit: a face whose normal is a
// rounding error off such a direction would flip between bins. Our default offset keeps every edge at least
// 0.02 from 0, ±1/2, ±√2/2, ±√3/2 and ±1 at the default s_nd (hash.rs `NormalBins`).
ivec3 normal_coord(vec3 n, float s_nd, float offset) {
    precise vec3 q = clamp(n, -1.0, 1.0) * s_nd + offset;   // precise: no fused multiply-add (CPU mirror)
    return ivec3(floor(q));
}

// eq. (4)-(6) with one base hash: H8D = h(F + h(nz + h(ny + h(nx + h(lod + h(pz + h(py + h(px)))))))).
// Ours (local edits, docs/algorithm.md): a non-zero region epoch E enters as one more step before F,
// h(F + h(E + H7D)); E = 0 leaves the paper's key unchanged.
#define HRTAO_H8D(H)                                                          \
    uint H##_8d(ivec3 c, int lod, ivec3 nq, uint F, uint E) {                  \
        uint k = H(uint(c.x));                                                \
        k = H(uint(c.y) + k);                                                 \
        k = H(uint(c.z) + k);                                                 \
        k = H(uint(lod) + k);                                                 \
        k = H(uint(nq.x) + k);                                                \
        k = H(uint(nq.y) + k);                                                \
        k = H(uint(nq.z) + k);                                                \
        if (E != 0u) k = H(E + k);                                            \
        return H(F + k);                                                      \
    }
HRTAO_H8D(h_index)
HRTAO_H8D(h_check)

struct CellKey {
    uint slot;      // index in the map (before probing)
    uint checksum;  // never EMPTY_CELL
};

// The key of integer cell `c` at LOD `lod` (eq. 4-6), its slot wrapped into the table.
CellKey cell_key_at(ivec3 c, int lod, ivec3 nq, uint F, uint E, uint capacity) {
    CellKey key;
    key.slot = h_index_8d(c, lod, nq, F, E) & (capacity - 1u);
    uint check = h_check_8d(c, lod, nq, F, E);
    key.checksum = check == EMPTY_CELL ? 1u : check;
    return key;
}

CellKey cell_key(vec3 p, vec3 n, int lod, float s_nd, float offset, uint F, uint E, uint capacity) {
    return cell_key_at(cell_coord(p, lod), lod, normal_coord(n, s_nd, offset), F, E, capacity);
}

// The region epoch table (local edits, ours; regions.rs). Cells of LOD `lod` lie in cubic regions of edge
// 2^(grid + 1), grid = max(lod, region_lod), where region_lod is the LOD of the largest finest cell (s_w_max):
// two cells across, never smaller than a cell, and one grid shared by all finer levels. A region is hashed
// with its grid into REGION_COUNT entries. Arithmetic shifts floor negative coordinates, so the region is
// exact on the CPU and the GPU.
uint region_entry(ivec3 r, int grid) {
    uint k = h_index(uint(grid));
    k = h_index(uint(r.x) + k);
    k = h_index(uint(r.y) + k);
    k = h_index(uint(r.z) + k);
    return k & (REGION_COUNT - 1u);
}
uint region_index(ivec3 c, int lod, int region_lod) {
    int grid = max(lod, region_lod);
    return region_entry(c >> clamp(grid + 1 - lod, 0, 31), grid);
}

#endif
