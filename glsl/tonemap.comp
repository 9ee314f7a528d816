#version 460
// Exposure + Reinhard on luminance, then sRGB encoding into an 8-bit target.
#include "common/scene.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 1, binding = 0, rgba16f) uniform readonly image2D hdr_in;
layout(set = 1, binding = 1, rgba8) uniform writeonly image2D ldr_out;

vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    vec3 c = imageLoad(hdr_in, px).rgb;
    if (frame.debug_view == DEBUG_NONE) {
        c *= frame.exposure;
        float l = dot(c, vec3(0.2126, 0.7152, 0.0722));
        c *= l > 0.0 ? (1.0 / (1.0 + l)) : 1.0;
    }
    imageStore(ldr_out, px, vec4(linear_to_srgb(c), 1.0));
}
