#version 460
// Primary visibility: one ray per pixel into the G-buffer (position, geometric normal facing the camera,
// shading normal, instance id, base colour). The ray is clipped to the region the section planes keep.
#define HRTAO_TRACES
#include "common.glsl"
#include "gpixel.glsl"
#include "clear.glsl"

// A band of push.w rows from row push.z (dispatch_plan.rs: an image of more pixels than a dispatch may trace is
// cut into bands of rows, as rtao.comp's); the first band resets the frame's counters.
void main() {
    if (push.z == 0u) clear_frame_counters();
    // Groups round the band up to whole work groups: the threads past its push.w rows are the next band's.
    if (THREAD_ID.y >= push.w) return;
    uvec2 pix = (THREAD_ID.xy + uvec2(0u, push.z)) * lattice() + uvec2(g.lattice_x, g.lattice_y);
    if (pix.x >= g.width || pix.y >= g.height) return;
    uint index = pix.y * g.width + pix.x;
    vec3 origin, dir;
    camera_ray(pix, origin, dir);
    float tmin = 0.0;
    float tmax = 1e30;
    bool kept = section_clip(origin, dir, tmin, tmax);
    HitRecord hit;
    GPixel px = gpixel_miss();
    if (kept && trace_closest(origin, dir, tmin, tmax, hit)) {
        uint geometry = InstanceRef(g.instances).v[hit.instance].geometry_base + hit.geometry;
        GeometryInfo geo = GeometryRef(g.geometries).v[geometry];
        uvec3 tri = IndexRef(geo.indices).v[hit.primitive];
        VertexRef verts = VertexRef(geo.vertices);
        vec3 a = hit.to_world * vec4(verts.v[tri.x], 1.0);
        vec3 b = hit.to_world * vec4(verts.v[tri.y], 1.0);
        vec3 c = hit.to_world * vec4(verts.v[tri.z], 1.0);
        px = gpixel_hit(a, b, c, hit.bary, hit.t, dir, hit.instance, geo, tri, mat3(hit.to_world));
    }
    GBufferRef(g.gbuffer).px[index] = px;
}
