// G-buffer samples as primary visibility writes them (a miss, or a hit on triangle a, b, c in world space).
// Mirrors primary.comp, which can adopt these helpers.
#ifndef HRTAO_GPIXEL_GLSL
#define HRTAO_GPIXEL_GLSL

GPixel gpixel_miss() {
    GPixel px;
    px.position = vec3(0.0);
    px.t = -1.0;
    px.normal = vec3(0.0, 0.0, 1.0);
    px.instance = NO_INSTANCE;
    px.color = vec3(0.0);
    px._pad = 0u;
    return px;
}

// Hit at barycentrics `bary` (of b and c) and distance t along the unit camera ray `dir`: the geometric normal
// is turned toward the camera.
GPixel gpixel_hit(vec3 a, vec3 b, vec3 c, vec2 bary, float t, vec3 dir, uint instance, vec3 color) {
    vec3 n = cross(b - a, c - a);
    float len = length(n);
    n = len > 0.0 ? n / len : -dir;
    if (dot(n, dir) > 0.0) n = -n;
    GPixel px;
    px.position = a + bary.x * (b - a) + bary.y * (c - a);
    px.t = t;
    px.normal = n;
    px.instance = instance;
    px.color = color;
    px._pad = 0u;
    return px;
}

#endif
