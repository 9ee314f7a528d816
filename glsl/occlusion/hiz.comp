#version 460
// One level of the depth pyramid (render/occlusion.rs): each texel is the
// FARTHEST (reversed-Z: minimum) depth of the 2x2 texels below it, so a box
// nearer than a texel's value is in front of everything drawn there. Odd
// sizes round up and the clamped reads repeat the last row/column, so every
// source texel is under some texel of the level.
#include "common/types.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

// Level 0 reads the depth buffer, the others the level below.
layout(set = SET_HIZ, binding = HIZ_SRC) uniform sampler2D src;
layout(set = SET_HIZ, binding = HIZ_DST, r32f) uniform writeonly image2D dst;

void main() {
    ivec2 d = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(d, imageSize(dst)))) return;
    ivec2 last = textureSize(src, 0) - 1;
    ivec2 s = 2 * d;
    float a = texelFetch(src, min(s, last), 0).r;
    float b = texelFetch(src, min(s + ivec2(1, 0), last), 0).r;
    float c = texelFetch(src, min(s + ivec2(0, 1), last), 0).r;
    float e = texelFetch(src, min(s + ivec2(1, 1), last), 0).r;
    imageStore(dst, d, vec4(min(min(a, b), min(c, e))));
}
