#version 460
// Primary visibility: one ray per pixel into the G-buffer (position, geometric normal facing the camera,
// instance id, base colour).
#include "common.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    vec3 origin, dir;
    camera_ray(pix, origin, dir);
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsOpaqueEXT, 0xFF, origin, 0.0, dir, 1e30);
    while (rayQueryProceedEXT(rq)) {
    }
    GPixel px;
    px.position = vec3(0.0);
    px.t = -1.0;
    px.normal = vec3(0.0, 0.0, 1.0);
    px.instance = NO_INSTANCE;
    px.color = vec3(0.0);
    px._pad = 0u;
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
        vec2 bary = rayQueryGetIntersectionBarycentricsEXT(rq, true);
        vec3 n = cross(b - a, c - a);
        float len = length(n);
        n = len > 0.0 ? n / len : -dir;
        if (dot(n, dir) > 0.0) n = -n;
        px.position = a + bary.x * (b - a) + bary.y * (c - a);
        px.t = rayQueryGetIntersectionTEXT(rq, true);
        px.normal = n;
        px.instance = instance;
        px.color = geo.color.rgb;
    }
    GBufferRef(g.gbuffer).px[index] = px;
}
