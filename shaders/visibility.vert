#version 460
// Rasterised primary visibility, vertex stage: pulls vertex gl_VertexIndex of the draw's geometry (an indexed
// draw over the geometry's own indices; the geometry is the draw's entry in the draw table, found by gl_DrawID;
// the fragment stage reads the primitive index, as a ray query reports it, from gl_PrimitiveID) for the visible
// instance gl_InstanceIndex, and projects it with the ray-traced camera.
#extension GL_EXT_buffer_reference : require
#extension GL_ARB_shader_draw_parameters : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "gpu_types.glsl"
#include "visibility.glsl"

layout(push_constant, scalar) uniform Push { RasterPush pc; };
layout(buffer_reference, scalar) readonly buffer GeometryRef { GeometryInfo v[]; };
layout(buffer_reference, scalar) readonly buffer VertexRef { vec3 v[]; };
layout(buffer_reference, scalar) readonly buffer GlobalsRef { FrameGlobals g; };
layout(buffer_reference, scalar) readonly buffer DrawGeometryRef { uint v[]; };

// Section planes clip the triangles: the clip distance is positive on the kept side (see section.glsl).
out float gl_ClipDistance[MAX_SECTIONS];

// (instance id, geometry, visible-instance slot): constant over the draw's instance.
layout(location = 0) flat out uvec3 vis;

void main() {
    uint geometry = DrawGeometryRef(pc.draw_geometries).v[pc.first_draw + uint(gl_DrawIDARB)];
    GeometryInfo geo = GeometryRef(pc.geometries).v[geometry];
    RasterInstance inst = RasterInstanceRef(pc.instances).v[gl_InstanceIndex];
    vec3 p = raster_to_world(inst, VertexRef(geo.vertices).v[gl_VertexIndex]);
    GlobalsRef globals = GlobalsRef(pc.globals);
    vec4 planes[MAX_SECTIONS] = vec4[MAX_SECTIONS](globals.g.section0, globals.g.section1, globals.g.section2);
    for (uint i = 0u; i < MAX_SECTIONS; ++i) {
        gl_ClipDistance[i] = i < globals.g.section_count ? planes[i].w - dot(planes[i].xyz, p) : 1.0;
    }
    vec3 d = p - pc.eye.xyz;
    // Projection matching camera_ray(): x, y in [-1, 1] across the image (row 0 at the top, as Vulkan's
    // viewport). Perspective: reversed infinite depth near / distance. Orthographic: w = 1 and reversed linear
    // depth 1 - distance / far (points behind the eye plane or beyond the scene are clipped).
    // The jitter moves the image by -jitter, so the pixel centre samples where camera_ray's jittered ray goes.
    float dist = dot(d, pc.cam_w.xyz);
    bool ortho = pc.projection == PROJECTION_ORTHOGRAPHIC;
    float w = ortho ? 1.0 : dist;
    vec2 xy = vec2(dot(d, pc.cam_u.xyz), -dot(d, pc.cam_v.xyz)) - pc.jitter_ndc * w;
    gl_Position = vec4(xy, ortho ? 1.0 - dist * pc.eye.w : pc.eye.w, w);
    vis = uvec3(inst.instance, geometry, uint(gl_InstanceIndex));
}
