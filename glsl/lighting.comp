#version 460
// Lighting / integrator pass, compute entry point. See common/lighting_main.glsl.
#include "common/lighting_main.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    shade_pixel(ivec2(gl_GlobalInvocationID.xy));
}
