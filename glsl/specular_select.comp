#version 460
// Pass `specular`, select kernel: lists the pixels whose primary hit spawns
// a reflection or refraction branch (no ray is traced here). See
// passes/specular.glsl.
#include "passes/specular.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    specular_select(ivec2(gl_GlobalInvocationID.xy));
}
