#version 460
// Primary visibility: one ray per pixel into the G-buffer (position, geometric normal facing the camera,
// instance id, base colour). Candidate hits (instances a section plane crosses) count where no plane cuts them.
#include "common.glsl"
#include "gpixel.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    vec3 dir = camera_dir(pix);
    vec3 origin = g.eye.xyz;
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsNoneEXT, 0xFF, origin, 0.0, dir, 1e30);
    while (rayQueryProceedEXT(rq)) {
        if (section_keeps(origin + rayQueryGetIntersectionTEXT(rq, false) * dir)) rayQueryConfirmIntersectionEXT(rq);
    }
    GPixel px = gpixel_miss();
    if (rayQueryGetIntersectionTypeEXT(rq, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
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
                        dir, instance, geo.color.rgb);
    }
    GBufferRef(g.gbuffer).px[index] = px;
}
