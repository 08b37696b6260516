#version 460
#include "common.glsl"
void main() {}
