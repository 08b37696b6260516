// Shared by the rasterised primary visibility (visibility.vert) and its G-buffer resolve (gbuffer_from_vis.comp).
#ifndef HRTAO_VISIBILITY_GLSL
#define HRTAO_VISIBILITY_GLSL

layout(buffer_reference, scalar) readonly buffer RasterInstanceRef { RasterInstance v[]; };

vec3 raster_to_world(RasterInstance inst, vec3 p) {
    vec4 h = vec4(p, 1.0);
    return vec3(dot(inst.row0, h), dot(inst.row1, h), dot(inst.row2, h));
}

#endif
