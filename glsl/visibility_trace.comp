#version 460
// Pass `visibility_trace`, compute entry point (ray-query or compute-BVH
// traversal, by variant: glsl/variants.txt). See passes/visibility_trace.glsl.
#include "passes/visibility_trace.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    visibility_pixel(ivec2(gl_GlobalInvocationID.xy));
}
