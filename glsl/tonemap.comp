#version 460
// Pass `tonemap`: exposure + Reinhard on luminance, then sRGB encoding into
// the 8-bit output.
#include "common/scene.glsl"
#include "common/srgb.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = TONEMAP_IN, rgba32f) uniform readonly image2D hdr_in;
layout(set = SET_PASS, binding = TONEMAP_OUT, rgba8) uniform writeonly image2D ldr_out;


void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    vec3 c = imageLoad(hdr_in, px).rgb;
    if (frame.debug_view == DEBUG_NONE) {
        c *= frame.exposure;
        float l = dot(c, vec3(0.2126, 0.7152, 0.0722));
        c *= l > 0.0 ? (1.0 / (1.0 + l)) : 1.0;
    }
    imageStore(ldr_out, px, vec4(srgb_encode(c), 1.0));
}
