#version 460
// Primary visibility: one ray per pixel into the G-buffer (position, geometric normal facing the camera,
// shading normal, instance id, base colour). The ray is clipped to the region the section planes keep.
#include "common.glsl"
#include "gpixel.glsl"
#include "clear.glsl"

void main() {
    clear_frame_counters();
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    vec3 origin, dir;
    camera_ray(pix, origin, dir);
    float tmin = 0.0;
    float tmax = 1e30;
    bool kept = section_clip(origin, dir, tmin, tmax);
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsOpaqueEXT, 0xFF, origin, tmin, dir, kept ? tmax : tmin);
    while (rayQueryProceedEXT(rq)) {
    }
    GPixel px = gpixel_miss();
    if (kept && rayQueryGetIntersectionTypeEXT(rq, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        uint instance = rayQueryGetIntersectionInstanceCustomIndexEXT(rq, true);
        uint geometry = InstanceRef(g.instances).v[instance].geometry_base +
                        rayQueryGetIntersectionGeometryIndexEXT(rq, true);
        GeometryInfo geo = GeometryRef(g.geometries).v[geometry];
        uvec3 tri = IndexRef(geo.indices).v[rayQueryGetIntersectionPrimitiveIndexEXT(rq, true)];
        VertexRef verts = VertexRef(geo.vertices);
        mat4x3 to_world = rayQueryGetIntersectionObjectToWorldEXT(rq, true);
        vec3 a = to_world * vec4(verts.v[tri.x], 1.0);
        vec3 b = to_world * vec4(verts.v[tri.y], 1.0);
        vec3 c = to_world * vec4(verts.v[tri.z], 1.0);
        px = gpixel_hit(a, b, c, rayQueryGetIntersectionBarycentricsEXT(rq, true), rayQueryGetIntersectionTEXT(rq, true),
                        dir, instance, geo, tri, mat3(to_world));
    }
    GBufferRef(g.gbuffer).px[index] = px;
}
