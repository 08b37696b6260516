// The one traversal behind every traced ray (included by common.glsl in passes that `#define HRTAO_TRACES`),
// with two implementations chosen at compile time (build.rs): a ray query in the pass's compute shader, or, in
// the pass's ray-generation variant (HRTAO_RAYGEN, the ray-tracing pipeline backend: pass.rs, rt_pipeline.rs),
// traceRayEXT: the rays that need a hit's attributes with the miss shader trace_miss.rmiss and the closest-hit
// shader trace_hit.rchit (a 72-byte payload), the others with their own pair and a 4-byte payload. Every ray is
// opaque (no any-hit shader).
#ifndef HRTAO_TRACE_GLSL
#define HRTAO_TRACE_GLSL
#include "trace_record.glsl"

layout(set = 0, binding = 0) uniform accelerationStructureEXT tlas;

#ifdef HRTAO_RAYGEN
layout(location = 0) rayPayloadEXT HitRecord trace_payload;

// The closest hit on the segment [tmin, tmax] of the ray from p along dir, with its attributes; false (h.t < 0)
// when it hits nothing or the segment is empty.
bool trace_closest(vec3 p, vec3 dir, float tmin, float tmax, out HitRecord h) {
    trace_payload.t = -1.0;
    if (tmax >= tmin) traceRayEXT(tlas, gl_RayFlagsOpaqueEXT, 0xFF, 0, 0, 0, p, tmin, dir, tmax, 0);
    h = trace_payload;
    return h.t >= 0.0;
}

// The rays that ask only a distance or whether they hit carry a 4-byte payload to their own miss shader (index 1)
// and hit group (record offset 1): trace_distance_miss.rmiss, trace_distance_hit.rchit.
layout(location = 1) rayPayloadEXT float trace_t;

// The distance of some hit (not necessarily the closest: the traversal stops at the first it finds) on the
// segment [tmin, tmax], or -1 when the segment hits nothing (no section clipping).
float segment_first_hit(vec3 p, vec3 dir, float tmin, float tmax) {
    if (tmax <= tmin) return -1.0;
    trace_t = -1.0;
    traceRayEXT(tlas, gl_RayFlagsOpaqueEXT | gl_RayFlagsTerminateOnFirstHitEXT, 0xFF, 1, 0, 1, p, tmin, dir, tmax, 1);
    return trace_t;
}

// Whether the segment hits anything: the miss shader alone answers (a hit leaves the payload as set here).
bool segment_occluded(vec3 p, vec3 dir, float tmin, float tmax) {
    if (tmax <= tmin) return false;
    trace_t = 0.0;
    traceRayEXT(tlas, gl_RayFlagsOpaqueEXT | gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT,
                0xFF, 1, 0, 1, p, tmin, dir, tmax, 1);
    return trace_t >= 0.0;
}
#else
bool trace_closest(vec3 p, vec3 dir, float tmin, float tmax, out HitRecord h) {
    h.t = -1.0;
    h.instance = 0u;
    h.geometry = 0u;
    h.primitive = 0u;
    h.bary = vec2(0.0);
    h.to_world = mat4x3(1.0);
    if (tmax < tmin) return false;
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsOpaqueEXT, 0xFF, p, tmin, dir, tmax);
    while (rayQueryProceedEXT(rq)) {
    }
    if (rayQueryGetIntersectionTypeEXT(rq, true) != gl_RayQueryCommittedIntersectionTriangleEXT) return false;
    h.t = rayQueryGetIntersectionTEXT(rq, true);
    h.instance = rayQueryGetIntersectionInstanceCustomIndexEXT(rq, true);
    h.geometry = rayQueryGetIntersectionGeometryIndexEXT(rq, true);
    h.primitive = rayQueryGetIntersectionPrimitiveIndexEXT(rq, true);
    h.bary = rayQueryGetIntersectionBarycentricsEXT(rq, true);
    h.to_world = rayQueryGetIntersectionObjectToWorldEXT(rq, true);
    return true;
}

float segment_first_hit(vec3 p, vec3 dir, float tmin, float tmax) {
    if (tmax <= tmin) return -1.0;
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsOpaqueEXT | gl_RayFlagsTerminateOnFirstHitEXT, 0xFF, p, tmin, dir, tmax);
    while (rayQueryProceedEXT(rq)) {
    }
    if (rayQueryGetIntersectionTypeEXT(rq, true) == gl_RayQueryCommittedIntersectionNoneEXT) return -1.0;
    return rayQueryGetIntersectionTEXT(rq, true);
}

bool segment_occluded(vec3 p, vec3 dir, float tmin, float tmax) { return segment_first_hit(p, dir, tmin, tmax) >= 0.0; }
#endif

// True when the ray from p along dir hits nothing within tmax (nor where a section plane cuts it away: the ray
// is clipped to the kept region).
bool ray_unoccluded(vec3 p, vec3 dir, float tmax) {
    float tmin = 0.0;
    if (!section_clip(p, dir, tmin, tmax)) return true;
    return !segment_occluded(p, dir, tmin, tmax);
}

#endif
