// G-buffer samples as primary visibility writes them (a miss, or a hit on triangle a, b, c in world space), for
// the ray-query pass (primary.comp) and the rasterised one (gbuffer_from_vis.comp). Needs common.glsl.
#ifndef HRTAO_GPIXEL_GLSL
#define HRTAO_GPIXEL_GLSL

const vec3 SECTION_COLOR = vec3(0.80, 0.22, 0.18);

GPixel gpixel_miss() {
    GPixel px;
    px.position = vec3(0.0);
    px.t = -1.0;
    px.normal = vec3(0.0, 0.0, 1.0);
    px.instance = NO_INSTANCE;
    px.color = vec3(0.0);
    px.flags = 0u;
    return px;
}

// Hit at barycentrics `bary` (of b and c) and distance t along the unit camera ray `dir`: the geometric normal
// is turned toward the camera. A back face seen through a section plane is the inside of a cut solid: the
// sample moves to the cap, where the ray entered the kept region, with the plane's normal and GPIXEL_SECTION.
GPixel gpixel_hit(vec3 a, vec3 b, vec3 c, vec2 bary, float t, vec3 dir, uint instance, vec3 color) {
    vec3 n = cross(b - a, c - a);
    float len = length(n);
    n = len > 0.0 ? n / len : -dir;
    bool back = dot(n, dir) > 0.0;
    if (back) n = -n;
    GPixel px;
    px.position = a + bary.x * (b - a) + bary.y * (c - a);
    px.t = t;
    px.normal = n;
    px.instance = instance;
    px.color = color;
    px.flags = 0u;
    if (back && g.section_count > 0u) {
        uint plane;
        vec3 origin = px.position - t * dir;
        float entry = section_entry(origin, dir, plane);
        if (plane < MAX_SECTIONS && entry <= t) {
            px.position = origin + entry * dir;
            px.t = entry;
            px.normal = section_plane(plane).xyz;
            px.color = SECTION_COLOR;
            px.flags = GPIXEL_SECTION;
        }
    }
    return px;
}

#endif
