// What a correction of the young map's corrections pass (corrections.comp) gets of the pixel it corrects. A
// correction is a shader file that declares itself by the line `// @correction order=N` (its place in each
// phase) and defines `float <file>_phase<k>(CorrectedPixel c, float a)`, the pixel's AO `a` after it, for each
// phase k it runs in; build.rs generates the pass's calls and each one's `additions::generated` constant from
// those. Needs common.glsl.
#ifndef HRTAO_CORRECTION_GLSL
#define HRTAO_CORRECTION_GLSL

struct CorrectedPixel {
    uint index;     // in the frame's images
    uvec2 pix;      // its coordinates
    GPixel px;      // its G-buffer sample
    uint samples;   // its cell's rays
};

#endif
