#version 460
// Pass `glossy`, select kernel: lists the pixels whose primary hit is glossy and has reflections
// selected (no ray is traced here). See passes/glossy.glsl.
#include "passes/glossy.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    glossy_select(ivec2(gl_GlobalInvocationID.xy));
}
