// Unit normals in one uint: octahedral mapping, 16-bit signed-normalised coordinates (gpu::pack_normal is the
// Rust side, tested to agree). Needs nothing.
#ifndef HRTAO_NORMAL_PACK_GLSL
#define HRTAO_NORMAL_PACK_GLSL

vec2 oct_wrap(vec2 v) { return (1.0 - abs(v.yx)) * mix(vec2(-1.0), vec2(1.0), greaterThanEqual(v, vec2(0.0))); }

uint pack_normal(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.z >= 0.0 ? n.xy : oct_wrap(n.xy);
    return packSnorm2x16(e);
}

vec3 unpack_normal(uint u) {
    vec2 e = unpackSnorm2x16(u);
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = oct_wrap(n.xy);
    return normalize(n);
}

#endif
