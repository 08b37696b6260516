#version 460
// Rasterised primary visibility, resolve: per pixel, the triangle the visibility draw found (instance, geometry,
// primitive, visible-instance slot; see visibility.vert) is intersected with the pixel's camera ray, giving the
// same G-buffer as the ray-query pass (primary.comp).
// push.xy: address of the visibility buffer (uvec4 per pixel), push.zw: address of the RasterInstance table.
#include "common.glsl"
#include "gpixel.glsl"
#include "visibility.glsl"
#include "clear.glsl"

layout(buffer_reference, scalar) readonly buffer VisRef { uvec4 v[]; };

void main() {
    clear_frame_counters();
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    vec3 origin, dir;
    camera_ray(pix, origin, dir);
    // The visibility image is the whole frame's (raster.rs: a round of slices draws it once).
    uvec4 vis = VisRef(packUint2x32(push.xy)).v[index];
    GPixel px = gpixel_miss();
    if (vis.x != NO_INSTANCE) {
        GeometryInfo geo = GeometryRef(g.geometries).v[vis.y];
        uvec3 tri = IndexRef(geo.indices).v[vis.z];
        VertexRef verts = VertexRef(geo.vertices);
        RasterInstance inst = RasterInstanceRef(packUint2x32(push.zw)).v[vis.w];
        vec3 a = raster_to_world(inst, verts.v[tri.x]);
        vec3 b = raster_to_world(inst, verts.v[tri.y]);
        vec3 c = raster_to_world(inst, verts.v[tri.z]);
        // Möller-Trumbore without the inside test: the rasteriser already chose this triangle for the pixel centre.
        vec3 e1 = b - a;
        vec3 e2 = c - a;
        vec3 p = cross(dir, e2);
        float det = dot(e1, p);
        if (det != 0.0) {
            float inv = 1.0 / det;
            vec3 s = origin - a;
            vec3 q = cross(s, e1);
            vec2 bary = vec2(dot(s, p), dot(dir, q)) * inv;
            float t = dot(e2, q) * inv;
            // The instance's rows are the object-to-world matrix's rows.
            mat3 m = transpose(mat3(inst.row0.xyz, inst.row1.xyz, inst.row2.xyz));
            if (t >= 0.0) px = gpixel_hit(a, b, c, bary, t, dir, vis.x, geo, tri, m);
        }
    }
    GBufferRef(g.gbuffer).px[index] = px;
}
