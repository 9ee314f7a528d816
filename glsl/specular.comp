#version 460
// Pass `specular`, compute entry point (ray-query or compute-BVH traversal, by
// variant: glsl/variants.txt). See passes/specular.glsl.
#include "passes/specular.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    specular_pixel(ivec2(gl_GlobalInvocationID.xy));
}
