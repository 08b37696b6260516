#version 460
// The closest-hit shader of every traced pass under the ray-tracing pipeline backend (trace.glsl): the hit's
// attributes, as a committed ray query reports them. Rays that need only whether they hit skip it.
#extension GL_EXT_ray_tracing : require
#include "trace_record.glsl"

layout(location = 0) rayPayloadInEXT HitRecord hit;
hitAttributeEXT vec2 bary;

void main() {
    hit.t = gl_HitTEXT;
    hit.instance = gl_InstanceCustomIndexEXT;
    hit.geometry = gl_GeometryIndexEXT;
    hit.primitive = gl_PrimitiveID;
    hit.bary = bary;
    hit.to_world = gl_ObjectToWorldEXT;
}
