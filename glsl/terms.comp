#version 460
// Pass `terms`, compute entry point; traversal per variant (glsl/variants.txt).
#include "passes/terms.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    terms_pixel(ivec2(gl_GlobalInvocationID.xy));
}
