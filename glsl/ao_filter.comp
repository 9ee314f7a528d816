#version 460
// Pass `ao filter`: denoises `ao`'s per-pixel visible share with a joint bilateral filter guided by the
// G-buffer over a window of (2 AO_FILTER_RADIUS_PX)² pixels, whole 4x4 tiles (each tile's rays are one
// stratified set of directions, passes/ao.glsl), keeping taps whose normal and plane through the
// centre's hit agree (against the pixel's footprint), so the share does not bleed across creases and
// silhouettes. Visible share and bounce are filtered apart and combined at the centre: the diffuse
// ambient radiance `composite` reads (rgb: what a white Lambertian surface exits, the SH irradiance
// times the share plus the bounce, over pi; a: the mean share, for the specular occlusion). The
// emitters' light on untraced specular lobes (demodulated by their albedo) is averaged with the same
// weights.
#include "common/gbuffer_read.glsl"
#include "common/env.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = AO_IN, rgba32f) uniform readonly image2D ao_in;
layout(set = SET_PASS, binding = AO_BOUNCE_IN, rgba32f) uniform readonly image2D ao_bounce_in;
layout(set = SET_PASS, binding = AO_VISIBILITY_OUT, rgba32f) uniform writeonly image2D ao_visibility;
#ifdef AO_EMITTER_SPECULAR
layout(set = SET_PASS, binding = AO_SPECULAR_IN, rgba32f) uniform readonly image2D ao_specular_in;
layout(set = SET_PASS, binding = AO_EMITTER_SPECULAR_OUT, rgba32f) uniform writeonly image2D emitter_specular;
#endif

vec3 ao_point(ivec2 px, float camera_distance) {
    return frame.camera_pos + camera_ray_dir(vec2(px) + 0.5) * camera_distance;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (outside_frame(px)) return;
    vec4 centre = imageLoad(ao_in, px);
    vec3 n = oct_decode(texelFetch(gb_normal, px, 0).x);
    if (centre.a <= 0.0) {
        vec3 sky = (frame.flags & FRAME_AO_SKY) != 0u ? ambient_radiance(n) : vec3(0.0);
        imageStore(ao_visibility, px, vec4(sky, 1.0));
#ifdef AO_EMITTER_SPECULAR
        imageStore(emitter_specular, px, vec4(0.0));
#endif
        return;
    }
    vec3 x = ao_point(px, centre.a);
    float footprint = pixel_spread_angle() * centre.a;
    vec3 sum = vec3(0.0), bounce = vec3(0.0), specular = vec3(0.0);
    float weights = 0.0;
    // A window of whole 4x4 tiles: each tile holds one stratified set of directions (passes/ao.glsl).
    const int r0 = int(AO_FILTER_RADIUS_PX);
    for (int dy = -r0; dy < r0; ++dy) {
        for (int dx = -r0; dx < r0; ++dx) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || outside_frame(q)) continue;
            vec4 tap = imageLoad(ao_in, q);
            if (tap.a <= 0.0) continue;
            vec3 nq = oct_decode(texelFetch(gb_normal, q, 0).x);
            float r = length(vec2(dx, dy));
            float wn = exp(-16.0 * max(1.0 - dot(n, nq), 0.0));
            float wp = exp(-abs(dot(n, ao_point(q, tap.a) - x)) / (footprint * max(r, 1.0)));
            float w = wn * wp;
            sum += w * tap.rgb;
            bounce += w * imageLoad(ao_bounce_in, q).rgb;
#ifdef AO_EMITTER_SPECULAR
            specular += w * imageLoad(ao_specular_in, q).rgb;
#endif
            weights += w;
        }
    }
    vec3 share = sum / weights;
    vec3 sky = (frame.flags & FRAME_AO_SKY) != 0u ? ambient_radiance(n) * share : vec3(0.0);
    vec3 radiance = sky + bounce / (weights * PI);
    imageStore(ao_visibility, px, vec4(radiance, (share.r + share.g + share.b) / 3.0));
#ifdef AO_EMITTER_SPECULAR
    imageStore(emitter_specular, px, vec4(specular / weights, 0.0));
#endif
}
