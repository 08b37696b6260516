// Unit normals in one uint: octahedral mapping, 16-bit signed-normalised coordinates (gpu::pack_normal is the
// Rust side, tested to agree); and the G-buffer's base colour in one uint. Needs nothing.
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

// A linear colour in one uint: sRGB-encoded 8-bit RGB (the output's precision), alpha 255.
uint pack_base_color(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    vec3 e = mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
    return packUnorm4x8(vec4(e, 1.0));
}

vec3 unpack_base_color(uint u) {
    vec3 e = unpackUnorm4x8(u).rgb;
    return mix(e / 12.92, pow((e + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), e));
}

#endif
