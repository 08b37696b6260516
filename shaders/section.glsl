// Section planes (section.rs, docs/algorithm.md): geometry where n·p > d is cut away for primary and AO rays.
// Instances a plane crosses are non-opaque in the TLAS, so their triangles come to the ray-query loops as
// candidates; `section_keeps` decides each one. Needs `g` (common.glsl).
#ifndef HRTAO_SECTION_GLSL
#define HRTAO_SECTION_GLSL

vec4 section_plane(uint i) { return i == 0u ? g.section0 : (i == 1u ? g.section1 : g.section2); }

// True when p is not cut away by any plane.
bool section_keeps(vec3 p) {
    for (uint i = 0u; i < g.section_count; ++i) {
        vec4 pl = section_plane(i);
        if (dot(pl.xyz, p) > pl.w) return false;
    }
    return true;
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
