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
    px.color = pack_base_color(vec3(0.0));
    px.flags = 0u;
    px.shading = pack_normal(px.normal);
    return px;
}

// The shading normal at barycentrics `bary` (of b and c) of triangle `tri` of `geo`: its vertex normals
// interpolated and carried to world space by the cofactor matrix of the object-to-world `m` (the inverse
// transpose up to a positive or negative scale, right for rotated, non-uniformly scaled and mirrored
// instances), turned to the side of the face normal `n` (toward the camera). `n` itself where the geometry has
// no normals or they cancel out: never a NaN.
vec3 shading_normal(GeometryInfo geo, uvec3 tri, vec2 bary, mat3 m, vec3 n) {
    if (geo.normals == 0ul) return n;
    UintRef ns = UintRef(geo.normals);
    vec3 o = (1.0 - bary.x - bary.y) * unpack_normal(ns.v[tri.x]) + bary.x * unpack_normal(ns.v[tri.y]) +
             bary.y * unpack_normal(ns.v[tri.z]);
    mat3 cof = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    vec3 w = cof * o;
    float len = length(w);
    if (!(len > 1e-30)) return n;
    w /= len;
    return dot(w, n) < 0.0 ? -w : w;
}

// Hit at barycentrics `bary` (of b and c) of triangle `tri` of `geo`, whose object-to-world 3x3 is `m`, and
// distance t along the unit camera ray `dir`: the geometric normal is turned toward the camera, the shading
// normal to its side. A back face seen through a section plane is the inside of a cut solid: the sample moves
// to the cap, where the ray entered the kept region, with the plane's normal and GPIXEL_SECTION.
GPixel gpixel_hit(vec3 a, vec3 b, vec3 c, vec2 bary, float t, vec3 dir, uint instance, GeometryInfo geo,
                  uvec3 tri, mat3 m) {
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
    px.color = pack_base_color(geo.color.rgb);
    px.flags = 0u;
    px.shading = pack_normal(shading_normal(geo, tri, bary, m, n));
    if (back && g.section_count > 0u) {
        uint plane;
        vec3 origin = px.position - t * dir;
        float entry = section_entry(origin, dir, plane);
        if (plane < MAX_SECTIONS && entry <= t) {
            px.position = origin + entry * dir;
            px.t = entry;
            px.normal = section_plane(plane).xyz;
            px.shading = pack_normal(px.normal);
            px.color = pack_base_color(SECTION_COLOR);
            px.flags = GPIXEL_SECTION;
        }
    }
    return px;
}

#endif
