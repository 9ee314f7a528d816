#version 460
// Fault injection for tests (render/passes/inject.rs): overwrites up to
// INJECT_MAX pixels of the HDR frame with given values (NaN, Inf, 1e30...)
// between `composite` and `luminance`, so the tone-mapping passes are
// tested on radiance no sanitized scene input can produce.
#extension GL_EXT_scalar_block_layout : require
#include "common/types.glsl"

layout(local_size_x = INJECT_MAX) in;
layout(set = SET_INJECT, binding = INJECT_HDR, rgba32f) uniform writeonly image2D hdr;
layout(scalar, push_constant) uniform Push {
    uvec4 pixels[INJECT_MAX];  // x, y, count (in [0].z), unused
    vec4 values[INJECT_MAX];
} pc;

void main() {
    uint i = gl_LocalInvocationID.x;
    if (i >= pc.pixels[0].z) return;
    imageStore(hdr, ivec2(pc.pixels[i].xy), pc.values[i]);
}
