#version 460
// Contact detail's screen-space obscurance (ours, contact_detail.glsl), while the map is young: over every
// pixel of the frame's slice, how much of the geometry around it rises above its tangent plane within R, into
// `obscurance`. It reads only the G-buffer, so it is dispatched right after primary visibility, beside the
// cell finder (one barrier for both).
#include "common.glsl"
#include "pool.glsl"
#include "contact_detail.glsl"

void main() {
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    FloatRef(g.obscurance).v[index] = px.t >= 0.0 ? obscurance(pix, px) : 0.0;
}
