#version 460
// Pass `glossy temporal`: blends this frame's glossy sample into the last frames' at the same surface
// point: the point (camera distance from `glossy`) projected with the previous frame's camera gives
// the history texel, kept where that texel saw the point at the distance expected (a disocclusion or a
// moved object fails it) and faded as the view direction turns against the lobe's width (a reflection
// follows the viewer). An exponential average; `glossy filter` then filters it spatially and writes
// it back as the next frame's history.
#include "common/gbuffer_read.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = GLOSSY_IN, rgba32f) uniform readonly image2D glossy_in;
layout(set = SET_PASS, binding = GLOSSY_HISTORY, rgba32f) uniform readonly image2D glossy_history;
layout(set = SET_PASS, binding = GLOSSY_ACCUM, rgba32f) uniform writeonly image2D glossy_accum;

// The history's weight for pixel px's sample c (camera distance c.a > 0); 0 where it has none.
float history_weight(ivec2 px, vec4 c, out vec3 history) {
    history = vec3(0.0);
    if ((frame.flags & FRAME_GLOSSY_HISTORY) == 0u) return 0.0;
    vec3 x = frame.camera_pos + camera_ray_dir(vec2(px) + 0.5) * c.a;
    vec4 clip = mat4(frame.prev_view_proj) * vec4(x, 1.0);
    if (clip.w <= 0.0) return 0.0;
    ivec2 q = ivec2(floor((clip.xy / clip.w * 0.5 + 0.5) * vec2(frame.resolution)));
    if (any(lessThan(q, ivec2(0))) || outside_frame(q)) return 0.0;
    vec4 h = imageLoad(glossy_history, q);
    float expected = distance(frame.prev_camera_pos, x);
    if (h.a <= 0.0 || abs(h.a - expected) > GLOSSY_TEMPORAL_DEPTH * expected) return 0.0;
    // How far the view turned at x, against the lobe's width alpha.
    float roughness = texelFetch(gb_material, px, 0).g;
    float a = max(roughness * roughness, 1e-3);
    vec3 now = normalize(frame.camera_pos - x), then = normalize(frame.prev_camera_pos - x);
    float turned = acos(clamp(dot(now, then), -1.0, 1.0)) / a;
    history = h.rgb;
    return (1.0 - GLOSSY_TEMPORAL_BLEND) * exp(-4.0 * turned * turned);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (outside_frame(px)) return;
    vec4 c = imageLoad(glossy_in, px);
    if (c.a > 0.0) {
        vec3 history;
        float w = history_weight(px, c, history);
        c.rgb = mix(c.rgb, history, w);
    }
    imageStore(glossy_accum, px, c);
}
