#version 460
// Pass `path`, compute entry point (ray-query or compute-BVH traversal, by
// variant: glsl/variants.txt). See path/path.glsl.
#include "path/path.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    path_pixel(ivec2(gl_GlobalInvocationID.xy));
}
