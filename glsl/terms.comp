#version 460
// Pass `terms`, compute entry point (ray-query or compute-BVH traversal,
// by variant: glsl/variants.txt). See passes/terms.glsl.
#include "passes/terms.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    terms_pixel(ivec2(gl_GlobalInvocationID.xy));
}
