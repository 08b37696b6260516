#version 460
// The miss shader of every traced pass under the ray-tracing pipeline backend (trace.glsl): no hit.
#extension GL_EXT_ray_tracing : require
#include "trace_record.glsl"

layout(location = 0) rayPayloadInEXT HitRecord hit;

void main() { hit.t = -1.0; }
