#version 460
// Pass `direct`, compute entry point; traversal per variant (glsl/variants.txt).
#include "passes/direct.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    direct_pixel(ivec2(gl_GlobalInvocationID.xy));
}
