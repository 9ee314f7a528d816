#version 460
// Pass `path`, compute entry point; traversal per variant (glsl/variants.txt).
#include "path/path.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    path_pixel(ivec2(gl_GlobalInvocationID.xy));
}
