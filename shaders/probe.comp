#version 460
// Probe rays (crates/hrtao-core/src/probes.rs: the walk's gravity and collision rays, a handful a frame): each
// ray of the ProbeRef buffer (push.xy its address, push.z the count) is clipped to the region the section
// planes keep and traced by the frame's ray backend (trace.glsl, as the AO's rays are; hidden instances are not
// in the TLAS); its closest hit is written beside it.
#define HRTAO_TRACES
#include "common.glsl"

layout(buffer_reference, scalar) buffer ProbeRef { ProbeHit hits[MAX_PROBE_RAYS]; ProbeRay rays[MAX_PROBE_RAYS]; };

void main() {
    uint i = THREAD_ID.x;
    if (THREAD_ID.y != 0u || i >= min(push.z, MAX_PROBE_RAYS)) return;
    ProbeRef probes = ProbeRef(packUint2x32(push.xy));
    ProbeRay r = probes.rays[i];
    ProbeHit h;
    h.normal = vec3(0.0);
    h.t = -1.0;
    h.instance = NO_INSTANCE;
    h.tag = r.tag;
    h.pad1 = 0u;
    h.pad2 = 0u;
    float tmin = r.tmin;
    float tmax = r.tmax;
    HitRecord hit;
    if (section_clip(r.origin, r.dir, tmin, tmax) && trace_closest(r.origin, r.dir, tmin, tmax, hit)) {
        uint geometry = InstanceRef(g.instances).v[hit.instance].geometry_base + hit.geometry;
        GeometryInfo geo = GeometryRef(g.geometries).v[geometry];
        uvec3 tri = IndexRef(geo.indices).v[hit.primitive];
        VertexRef verts = VertexRef(geo.vertices);
        vec3 a = hit.to_world * vec4(verts.v[tri.x], 1.0);
        vec3 b = hit.to_world * vec4(verts.v[tri.y], 1.0);
        vec3 c = hit.to_world * vec4(verts.v[tri.z], 1.0);
        vec3 n = cross(b - a, c - a);
        float len = length(n);
        n = len > 0.0 ? n / len : -r.dir;
        h.normal = dot(n, r.dir) > 0.0 ? -n : n;
        h.t = hit.t;
        h.instance = hit.instance;
    }
    probes.hits[i] = h;
}
