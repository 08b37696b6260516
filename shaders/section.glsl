// Section planes (section.rs, docs/algorithm.md): geometry where n·p > d is cut away for primary and AO rays.
// Needs `g` (common.glsl).
#ifndef HRTAO_SECTION_GLSL
#define HRTAO_SECTION_GLSL

vec4 section_plane(uint i) { return i == 0u ? g.section0 : (i == 1u ? g.section1 : g.section2); }

// Clips the ray interval [tmin, tmax] of o + t dir to the kept region. The kept region (the intersection of the
// planes' kept half-spaces) is convex, so a ray meets it over one interval and every hit inside the interval is
// kept: the rays stay opaque (no per-candidate plane tests) and traversal skips the cut parts of the instances
// the planes cross. False when nothing is left.
bool section_clip(vec3 o, vec3 dir, inout float tmin, inout float tmax) {
    for (uint i = 0u; i < g.section_count; ++i) {
        vec4 pl = section_plane(i);
        float s = dot(pl.xyz, o) - pl.w;
        float v = dot(pl.xyz, dir);
        if (v > 0.0) {
            tmax = min(tmax, -s / v);
        } else if (v < 0.0) {
            tmin = max(tmin, -s / v);
        } else if (s > 0.0) {
            return false;
        }
    }
    return tmin < tmax;
}

// Where the ray o + t dir enters the kept region: the largest crossing t of the planes whose cut side holds o
// (0 when o is kept), and the plane crossed there (MAX_SECTIONS when none).
float section_entry(vec3 o, vec3 dir, out uint plane) {
    float t = 0.0;
    plane = MAX_SECTIONS;
    for (uint i = 0u; i < g.section_count; ++i) {
        vec4 pl = section_plane(i);
        float s = dot(pl.xyz, o) - pl.w;
        float v = dot(pl.xyz, dir);
        if (s > 0.0 && v < 0.0 && -s / v > t) {
            t = -s / v;
            plane = i;
        }
    }
    return t;
}

#endif
