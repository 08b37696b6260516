#version 460
// Composite: base colour x AO with a soft key light, over a background gradient, sRGB-encoded RGBA8.
#include "common.glsl"

vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

vec3 false_color(uint v) {
    uint h = pcg_hash(v);
    return vec3(float(h & 255u), float((h >> 8) & 255u), float((h >> 16) & 255u)) / 255.0;
}

vec3 heat(float x) {
    x = clamp(x, 0.0, 1.0);
    return clamp(vec3(1.5 - abs(4.0 * x - 3.0), 1.5 - abs(4.0 * x - 2.0), 1.5 - abs(4.0 * x - 1.0)), 0.0, 1.0);
}

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    float ao = g.mode == MODE_NO_AO ? 1.0 : clamp(FloatRef(g.ao).v[index], 0.0, 1.0);
    vec3 color;
    if (px.t < 0.0) {
        float y = (float(pix.y) + 0.5) / float(g.height);
        color = mix(g.background_top.rgb, g.background_bottom.rgb, y);
    } else if (g.mode == MODE_DEBUG_CELLS || g.mode == MODE_DEBUG_LOD || g.mode == MODE_DEBUG_SAMPLES) {
        PixelCells pc = PixelCellRef(g.pixel_cells).v[index];
        if (g.mode == MODE_DEBUG_CELLS) {
            color = false_color(pc.cells[0]);
        } else if (g.mode == MODE_DEBUG_LOD) {
            uint used = UintRef(g.ao_lod).v[index];
            color = used >= LOD_COUNT ? vec3(0.0) : heat(float(used) / float(LOD_COUNT - 1u));
        } else {
            uint cell = pc.cells[0];
            uint s = cell < g.hash_capacity ? CellRef(g.hash_cells).v[cell].samples : 0u;
            color = heat(log2(1.0 + float(s)) / log2(1.0 + float(max(g.max_samples, 1u))));
        }
    } else {
        vec3 view = normalize(px.position - g.eye.xyz);
        // Key light from above-left of the viewer, plus a soft fill: a CAD-viewport look.
        vec3 key = normalize(-view + 0.6 * normalize(g.cam_v.xyz) - 0.4 * normalize(g.cam_u.xyz));
        float diffuse = max(dot(px.normal, key), 0.0);
        float light = 0.4 + 0.6 * diffuse;
        vec3 base = (g.flags & FLAG_SHADED) != 0u ? px.color : vec3(0.8);
        color = base * ao * light;
        if ((InstanceRef(g.instances).v[px.instance].flags & INSTANCE_SELECTED) != 0u) {
            color = mix(color, vec3(1.0, 0.55, 0.1), 0.45);
        }
    }
    uvec3 c = uvec3(linear_to_srgb(color) * 255.0 + 0.5);
    if ((g.flags & FLAG_OUTPUT_BGRA) != 0u) c = c.bgr;
    UintRef(g.output_rgba).v[index] = c.r | (c.g << 8) | (c.b << 16) | (255u << 24);
}
