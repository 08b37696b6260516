#version 460
// Rasterised primary visibility, fragment stage: the nearest triangle's ids (see visibility.vert).
layout(location = 0) flat in uvec4 vis;
layout(location = 0) out uvec4 out_vis;

void main() { out_vis = vis; }
