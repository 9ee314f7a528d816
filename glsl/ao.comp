#version 460
// Pass `ao`, compute entry point (ray-query or compute-BVH traversal, by variant: glsl/variants.txt).
// See passes/ao.glsl.
#include "passes/ao.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    ao_pixel(ivec2(gl_GlobalInvocationID.xy));
}
