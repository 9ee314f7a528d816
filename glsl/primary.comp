#version 460
// Pass `primary`, compute entry point; traversal per variant (glsl/variants.txt).
#include "passes/primary.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    primary_pixel(ivec2(gl_GlobalInvocationID.xy));
}
