#version 460
// Pass `primary`, compute entry point (ray-query or compute-BVH traversal, by
// variant: glsl/variants.txt). See passes/primary.glsl.
#include "passes/primary.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    primary_pixel(ivec2(gl_GlobalInvocationID.xy));
}
