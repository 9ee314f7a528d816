#version 460
// Pass `glossy`, one lobe sample per listed pixel, compute entry point (ray-query or compute-BVH
// traversal, by variant: glsl/variants.txt). See passes/glossy.glsl.
#include "passes/glossy.glsl"

layout(local_size_x = WORK_GROUP_SIZE) in;

void main() {
    glossy_listed(gl_GlobalInvocationID.x);
}
