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

// eq. (5)'s normal quantisation, with bins centred on the integers: floor(n s_nd + 1/2). The paper's
// floor(n s_nd) puts bin edges exactly on axis-aligned normals, the most common normals in CAD, so a face
// whose normal is a rounding error off an axis would flip between bins.
ivec3 normal_coord(vec3 n, float s_nd) {
    precise vec3 q = clamp(n, -1.0, 1.0) * s_nd + 0.5;   // precise: no fused multiply-add (CPU mirror)
    return ivec3(floor(q));
}

// eq. (4)-(6) with one base hash: H8D = h(F + h(nz + h(ny + h(nx + h(lod + h(pz + h(py + h(px)))))))).
#define HRTAO_H8D(H)                                                          \
    uint H##_8d(ivec3 c, int lod, ivec3 nq, uint F) {                          \
        uint k = H(uint(c.x));                                                \
        k = H(uint(c.y) + k);                                                 \
        k = H(uint(c.z) + k);                                                 \
        k = H(uint(lod) + k);                                                 \
        k = H(uint(nq.x) + k);                                                \
        k = H(uint(nq.y) + k);                                                \
        k = H(uint(nq.z) + k);                                                \
        return H(F + k);                                                      \
    }
HRTAO_H8D(h_index)
HRTAO_H8D(h_check)

struct CellKey {
    uint slot;      // index in the map (before probing)
    uint checksum;  // never EMPTY_CELL
};

// The key of integer cell `c` at LOD `lod` (eq. 4-6), its slot wrapped into the table.
CellKey cell_key_at(ivec3 c, int lod, ivec3 nq, uint F, uint capacity) {
    CellKey key;
    key.slot = h_index_8d(c, lod, nq, F) & (capacity - 1u);
    uint check = h_check_8d(c, lod, nq, F);
    key.checksum = check == EMPTY_CELL ? 1u : check;
    return key;
}

CellKey cell_key(vec3 p, vec3 n, int lod, float s_nd, uint F, uint capacity) {
    return cell_key_at(cell_coord(p, lod), lod, normal_coord(n, s_nd), F, capacity);
}

#endif
