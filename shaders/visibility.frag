#version 460
// Rasterised primary visibility, fragment stage: the nearest triangle's ids (instance, geometry, primitive within
// the draw's geometry, visible-instance slot; see visibility.vert). gl_PrimitiveID counts the triangles of the
// draw, as the geometry's primitive index of a ray query (needs the geometryShader feature).
layout(location = 0) flat in uvec3 vis;
layout(location = 0) out uvec4 out_vis;

void main() { out_vis = uvec4(vis.x, vis.y, uint(gl_PrimitiveID), vis.z); }
