#version 460
// Pass `visibility_trace`, compute entry point; traversal per variant (glsl/variants.txt).
#include "passes/visibility_trace.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    visibility_pixel(ivec2(gl_GlobalInvocationID.xy));
}
