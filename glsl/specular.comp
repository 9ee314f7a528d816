#version 460
// Pass `specular`, the chain over the listed pixels, compute entry point
// (ray-query or compute-BVH traversal, by variant: glsl/variants.txt). See
// passes/specular.glsl.
#include "passes/specular.glsl"

layout(local_size_x = WORK_GROUP_SIZE) in;

void main() {
    specular_listed(gl_GlobalInvocationID.x);
}
