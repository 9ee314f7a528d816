#version 460
// Pass `tonemap`: exposure, tone curve, sRGB encode to 8 bits. NaN/Inf pixels are counted
// (RAY_COUNTER_BAD_PIXELS) and shown magenta, as in the render command's PNGs: never hidden and never
// spread (no reduction reads them).
#extension GL_EXT_scalar_block_layout : require
#include "common/scene.glsl"
#include "common/srgb.glsl"
#include "common/tonemap.glsl"
#include "common/exposure_state.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = TONEMAP_IN, rgba32f) uniform readonly image2D hdr_in;
layout(set = SET_PASS, binding = TONEMAP_OUT, rgba8) uniform writeonly image2D ldr_out;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    vec3 c = imageLoad(hdr_in, px).rgb;
    if (any(isnan(c)) || any(isinf(c))) {
        atomicAdd(ray_counts[RAY_COUNTER_BAD_PIXELS], 1u);
        imageStore(ldr_out, px, vec4(1.0, 0.0, 1.0, 1.0));
        return;
    }
    if (frame.debug_view == DEBUG_NONE) {
        bool automatic = frame.auto_exposure != AUTO_EXPOSURE_OFF;
        float exposure = automatic ? exposure_state.exposure : frame.exposure;
        // Bounded so no curve overflows (1e18 squared is finite).
        c = min(max(c, vec3(0.0)) * exposure, vec3(1e18));
        // No explicit white point: the frame's brightest pixel, exposed.
        float white = frame.white > 0.0 ? frame.white : exposure_state.max_luminance * exposure;
        c = tonemap_apply(frame.tonemap, c, white);
    }
    imageStore(ldr_out, px, vec4(srgb_encode(c), 1.0));
}
