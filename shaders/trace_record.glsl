// What a traced ray found, the same from a ray query (trace.glsl) and from the ray-tracing pipeline's closest-hit
// and miss shaders (trace_hit.rchit, trace_miss.rmiss), which return it as the ray's payload. Shader-only: no Rust
// side reads it.
#ifndef HRTAO_TRACE_RECORD_GLSL
#define HRTAO_TRACE_RECORD_GLSL

struct HitRecord {
    // Distance along the ray; negative: no hit.
    float t;
    // The instance's custom index, the geometry's index in its BLAS and the triangle's index in the geometry.
    uint instance;
    uint geometry;
    uint primitive;
    // Barycentrics of the hit (of vertices 1 and 2).
    vec2 bary;
    mat4x3 to_world;
};

#endif
