#version 460
// The miss shader of the rays that ask only a distance or whether they hit (trace.glsl `segment_first_hit`,
// `segment_occluded`) under the ray-tracing pipeline backend: no hit.
#extension GL_EXT_ray_tracing : require

layout(location = 1) rayPayloadInEXT float hit_t;

void main() { hit_t = -1.0; }
