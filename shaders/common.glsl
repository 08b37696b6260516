// Shared by every pass: extensions, the generated GPU types, the one descriptor set, buffer references,
// camera rays, ray-origin offsetting and sampling helpers.
#ifndef HRTAO_COMMON_GLSL
#define HRTAO_COMMON_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference2 : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_KHR_memory_scope_semantics : require
// A pass that traces rays `#define`s HRTAO_TRACES before including this file; build.rs compiles it as a compute
// shader with ray queries and, where the device traces with pipelines, also as a ray-generation shader
// (HRTAO_RAYGEN). Passes that do not trace declare no ray-tracing capability at all.
#if defined(HRTAO_RAYGEN)
#extension GL_EXT_ray_tracing : require
#elif defined(HRTAO_TRACES)
#extension GL_EXT_ray_query : require
#endif

#include "gpu_types.glsl"
#include "hash.glsl"

// The pass's thread: a compute shader's global invocation, or a ray-generation shader's launch index (launched
// over the compute dispatch's groups times WORKGROUP_SIZE in x and y: recorder.rs), the same for every pixel.
#ifdef HRTAO_RAYGEN
#define THREAD_ID gl_LaunchIDEXT
#else
layout(local_size_x = WORKGROUP_SIZE, local_size_y = WORKGROUP_SIZE, local_size_z = 1) in;
#define THREAD_ID gl_GlobalInvocationID
#endif

layout(set = 0, binding = 1, scalar) readonly buffer GlobalsBlock { FrameGlobals g; };
layout(push_constant) uniform Push { uvec4 push; };

#include "section.glsl"
#include "normal_pack.glsl"

layout(buffer_reference, scalar) buffer GBufferRef { GPixel px[]; };
layout(buffer_reference, scalar) readonly buffer InstanceRef { InstanceInfo v[]; };
layout(buffer_reference, scalar) readonly buffer GeometryRef { GeometryInfo v[]; };
layout(buffer_reference, scalar) readonly buffer VertexRef { vec3 v[]; };
layout(buffer_reference, scalar) readonly buffer IndexRef { uvec3 v[]; };
layout(buffer_reference, scalar) buffer FloatRef { float v[]; };
layout(buffer_reference, scalar) buffer UintRef { uint v[]; };
layout(buffer_reference, scalar) buffer CellRef { HashCell v[]; };
layout(buffer_reference, scalar) buffer PixelCellRef { PixelCells v[]; };
layout(buffer_reference, scalar) buffer StatsRef { uint counters[STAT_COUNT]; uint64_t rays[RAYS_COUNT]; };
layout(buffer_reference, scalar) buffer PixelRaysRef { PixelRays v[]; };
layout(buffer_reference, scalar) buffer PixelAccumRef { PixelAccum v[]; };

const float PI = 3.14159265358979;

void stat_add(uint which, uint v) { atomicAdd(StatsRef(g.stats).counters[which], v); }
// The non-finite guard (ours): NaN or infinity must never enter the map's sums or the still accumulation, where
// it would spread through the filter and every later frame (a GPU may return NaN where GLSL leaves a result
// undefined). A value found non-finite is replaced by `safe` and counted (STAT_NON_FINITE,
// `FrameReport::non_finite`): 0 on a sound device.
bool is_finite(float v) { return !(isnan(v) || isinf(v)); }
float finite_or_count(float v, float safe) {
    if (is_finite(v)) return v;
    stat_add(STAT_NON_FINITE, 1u);
    return safe;
}
// The same without the count, for the composite: its inputs were counted where they were made (the update, the
// resolve), and it writes no statistics (the frame's statistics copy shares its barrier).
float finite_or(float v, float safe) { return is_finite(v) ? v : safe; }
// Ray counts (u64: no wrap at 4K x 1024 rays).
void rays_add(uint which, uint v) { atomicAdd(StatsRef(g.stats).rays[which], uint64_t(v)); }

// The lattice of pixels this frame draws (ours, slices): every lattice()-th pixel in x and y.
uint lattice() { return max(g.lattice, 1u); }

// The pixel of this invocation (passes over the image are dispatched over the frame's lattice), or false when
// it lies outside the image.
bool pixel_coords(out uvec2 pix, out uint index) {
    pix = THREAD_ID.xy * lattice() + uvec2(g.lattice_x, g.lattice_y);
    index = pix.y * g.width + pix.x;
    return pix.x < g.width && pix.y < g.height;
}

// The neighbour d steps away among the pixels this frame draws (d lattice steps): passes that read what their
// neighbours found this frame (filter, pools, obscurance) read these.
ivec2 neighbour(uvec2 pix, ivec2 d) { return ivec2(pix) + d * int(lattice()); }

// The entry of this invocation in a queue of `count` pixels, in a pass dispatched indirectly over it
// (queue_args.comp: 2-D groups of WORKGROUP_SIZE^2 threads).
// A ray-generation shader numbers its launch index as the compute shader's groups and local invocations would.
bool queue_entry(uint count, out uint q) {
#ifdef HRTAO_RAYGEN
    uvec2 group_id = gl_LaunchIDEXT.xy / WORKGROUP_SIZE;
    uvec2 local = gl_LaunchIDEXT.xy % WORKGROUP_SIZE;
    uint group = group_id.y * (gl_LaunchSizeEXT.x / WORKGROUP_SIZE) + group_id.x;
    q = group * (WORKGROUP_SIZE * WORKGROUP_SIZE) + local.y * WORKGROUP_SIZE + local.x;
#else
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    q = group * (WORKGROUP_SIZE * WORKGROUP_SIZE) + gl_LocalInvocationIndex;
#endif
    return q < count;
}

// A moving frame over a settled map (ours): few cells are young, scattered; our first-frame additions (extra
// filter iterations, level blend) leave it, and it resolves and filters as the paper does.
bool navigation_frame() { return g.still_index == 0u && (g.flags & FLAG_YOUNG_MAP) == 0u; }

// Still-camera refinement frame (ours): every pixel traces its own rays.
bool refine_frame() { return (g.flags & FLAG_REFINE) != 0u && g.still_index > 0u; }

// A frame of a still image that refines (ours): refinement frames, and the first round of slices (the view
// rests). Its cell estimate is the prior of the pixels' own rays.
bool still_prior_frame() { return (g.flags & FLAG_REFINE) != 0u && (g.still_index > 0u || lattice() > 1u); }

bool camera_orthographic() { return g.projection == PROJECTION_ORTHOGRAPHIC; }

// The camera ray through the pixel centre moved by this frame's jitter (Camera::ray): perspective, from the eye
// with the vertical field of view spanning the image height; orthographic, along cam_w from the plane through
// the eye, the image spanning 2 cam_u x 2 cam_v world units.
void camera_ray(uvec2 pix, out vec3 origin, out vec3 dir) {
    vec2 ndc = (vec2(pix) + 0.5 + g.jitter) / vec2(g.width, g.height) * 2.0 - 1.0;
    vec3 offset = ndc.x * g.cam_u.xyz - ndc.y * g.cam_v.xyz;
    if (camera_orthographic()) {
        origin = g.eye.xyz + offset;
        dir = g.cam_w.xyz;
    } else {
        origin = g.eye.xyz;
        dir = normalize(g.cam_w.xyz + offset);
    }
}

// Unit direction from the camera toward the visible point p.
vec3 view_dir(vec3 p) { return camera_orthographic() ? g.cam_w.xyz : normalize(p - g.eye.xyz); }

// World size of one internal pixel at hit distance t (cam_v spans half the image height).
float pixel_world_size(float t) {
    return (camera_orthographic() ? 1.0 : t) * 2.0 * length(g.cam_v.xyz) / float(g.height);
}

// World size of one step between the neighbours of `neighbour` (a pixel, or the lattice's spacing).
float step_world_size(float t) { return pixel_world_size(t) * float(lattice()); }

// Slices of a still image (ours): the filter taps at full resolution, where the pixels of the other slices
// hold the cell estimate they resolved when last drawn (`SlicePrior`), so every slice filters the field a whole
// frame would (a slice's own sub-grid alone gave each slice's pixels a differently smoothed field: a pattern
// of the lattice's period). Whole frames and moving frames tap their own pixels as before.
bool filter_full_taps() { return still_prior_frame() && lattice() > 1u; }
// Whether `q` is one of the pixels this frame draws.
bool in_slice(uvec2 q) { return q % lattice() == uvec2(g.lattice_x, g.lattice_y); }
// The world size of the filter's step: a pixel with full taps, else the spacing of the frame's lattice.
float filter_step_size(float t) { return filter_full_taps() ? pixel_world_size(t) : step_world_size(t); }

// Offsets a ray origin off the surface along the normal, robust at any scale
// (Waechter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems, ch. 6).
vec3 offset_ray(vec3 p, vec3 n) {
    const float origin = 1.0 / 32.0;
    const float float_scale = 1.0 / 65536.0;
    const float int_scale = 256.0;
    ivec3 of_i = ivec3(int_scale * n);
    vec3 p_i = vec3(intBitsToFloat(floatBitsToInt(p.x) + ((p.x < 0.0) ? -of_i.x : of_i.x)),
                    intBitsToFloat(floatBitsToInt(p.y) + ((p.y < 0.0) ? -of_i.y : of_i.y)),
                    intBitsToFloat(floatBitsToInt(p.z) + ((p.z < 0.0) ? -of_i.z : of_i.z)));
    return vec3(abs(p.x) < origin ? p.x + float_scale * n.x : p_i.x,
                abs(p.y) < origin ? p.y + float_scale * n.y : p_i.y,
                abs(p.z) < origin ? p.z + float_scale * n.z : p_i.z);
}

// Orthonormal basis around n (Duff et al. 2017).
void basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Cosine-weighted direction around n from a point u of the unit square.
vec3 cosine_direction(vec3 n, vec2 u) {
    vec3 t, b;
    basis(n, t, b);
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    return normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(0.0, 1.0 - u.x)) * n);
}

float uint_to_unit(uint v) { return float(v >> 8) * (1.0 / 16777216.0); }

// The R2 low-discrepancy sequence (Roberts 2018), point i, rotated by `shift` (Cranley-Patterson), in 0.32
// fixed point: exact for every i (a float alpha * i loses precision past about 2^16 points).
vec2 r2_point(uint i, uvec2 shift) {
    const uvec2 alpha = uvec2(3242174889u, 2447445414u);   // round(2^32 * (0.7548776662..., 0.5698402909...))
    uvec2 x = shift + alpha * i;
    return vec2(uint_to_unit(x.x), uint_to_unit(x.y));
}

// The Cranley-Patterson rotation of a pixel's own R2 sequence (per-pixel RTAO and still-camera refinement).
uvec2 pixel_shift(uint index) {
    return uvec2(h_check(index * 2u + 0x9e3779b9u), h_index(index * 2u + 1u + 0x7f4a7c15u));
}

#ifdef HRTAO_TRACES
#include "trace.glsl"
#endif

#endif
