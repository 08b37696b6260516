#version 460
// Contact detail's screen-space obscurance (ours, contact_detail.glsl), while the map is young: over every
// pixel of the frame's slice, how much of the geometry around it rises above its tangent plane within R, into
// its buffer (push.zw), whose fit sums its first thread resets. It reads only the G-buffer, so it is
// dispatched right after primary visibility, beside the cell finder (one barrier for both).
#include "common.glsl"
#include "pool.glsl"
#include "contact_detail.glsl"

void main() {
    ContactDetailRef cd = ContactDetailRef(packUint2x32(push.zw));
    if (THREAD_ID.xy == uvec2(0u)) {
        cd.sums[0] = int64_t(0);
        cd.sums[1] = int64_t(0);
    }
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    cd.obscurance[index] = px.t >= 0.0 ? obscurance(pix, px) : 0.0;
}
