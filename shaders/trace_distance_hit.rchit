#version 460
// The closest-hit shader of the rays that ask only a distance (trace.glsl `segment_first_hit`) under the
// ray-tracing pipeline backend: a 4-byte payload, where trace_hit.rchit fills a 72-byte hit record.
#extension GL_EXT_ray_tracing : require

layout(location = 1) rayPayloadInEXT float hit_t;

void main() { hit_t = gl_HitTEXT; }
