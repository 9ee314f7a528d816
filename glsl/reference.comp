#version 460
// Pass `reference`, compute entry point; traversal per variant (glsl/variants.txt).
#include "passes/reference.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    reference_pixel(ivec2(gl_GlobalInvocationID.xy));
}
