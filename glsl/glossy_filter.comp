#version 460
// Pass `glossy filter`: denoises the glossy correction (the frame's sample; variant TEMPORAL: `glossy
// temporal`'s blend of the frames' samples, kept as the next frame's history) with a joint bilateral
// filter guided by the G-buffer, then scales it by the lobe's albedo; variant HAS_SPECULAR adds the
// mirror / glass chain, so `composite` reads one specular input. Taps: GLOSSY_FILTER_TAPS on a
// golden-angle spiral turned per pixel, over a radius of the lobe's width as seen from the camera
// (alpha over the pixel's angle, capped), kept where normal (against the lobe's width), plane distance
// (against the pixel's footprint) and roughness agree.
#include "common/gbuffer_read.glsl"
#include "common/integrator.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = GLOSSY_IN, rgba32f) uniform readonly image2D glossy_in;
#ifdef HAS_SPECULAR
layout(set = SET_PASS, binding = SPECULAR_IN, rgba32f) uniform readonly image2D specular_in;
#endif
layout(set = SET_PASS, binding = REFLECTED_OUT, rgba32f) uniform writeonly image2D reflected_out;
#ifdef TEMPORAL
layout(set = SET_PASS, binding = GLOSSY_HISTORY, rgba32f) uniform writeonly image2D glossy_history;
#endif

struct Guide {
    vec3 n;
    vec3 x;
    float roughness;
};

Guide guide_at(ivec2 px, float camera_distance) {
    Guide g;
    g.n = oct_decode(texelFetch(gb_normal, px, 0).x);
    g.x = frame.camera_pos + camera_ray_dir(vec2(px) + 0.5) * camera_distance;
    g.roughness = texelFetch(gb_material, px, 0).g;
    return g;
}

// `lobe_roughness`: the sampled lobe's (the base's or a coat's), which sets the radius.
vec3 filtered_correction(ivec2 px, vec4 centre, float lobe_roughness) {
    Guide c = guide_at(px, centre.a);
    float a = max(lobe_roughness * lobe_roughness, 1e-3);
    float spread = pixel_spread_angle();
    float radius = min(GLOSSY_FILTER_SCALE * a / spread, GLOSSY_FILTER_MAX_PX);
    vec3 sum = centre.rgb;
    float weights = 1.0;
    if (radius < 1.0) return sum;
    float footprint = spread * centre.a;
    float turn = float(pcg_hash(uint(px.x) ^ pcg_hash(uint(px.y)))) * (2.0 * PI / 4294967296.0);
    for (uint i = 0u; i < GLOSSY_FILTER_TAPS; ++i) {
        float r = radius * sqrt((float(i) + 0.5) / float(GLOSSY_FILTER_TAPS));
        float phi = turn + float(i) * 2.39996323;
        ivec2 q = px + ivec2(round(r * vec2(cos(phi), sin(phi))));
        if (q == px || any(lessThan(q, ivec2(0))) || outside_frame(q)) continue;
        vec4 tap = imageLoad(glossy_in, q);
        if (tap.a <= 0.0) continue;
        Guide g = guide_at(q, tap.a);
        // The reflected direction turns twice as fast as the normal; against the lobe's width alpha.
        float wn = exp(-8.0 * max(1.0 - dot(c.n, g.n), 0.0) / (a * a));
        float wp = exp(-abs(dot(c.n, g.x - c.x)) / (2.0 * footprint * max(r, 1.0)));
        float wr = exp(-20.0 * abs(c.roughness - g.roughness));
        float w = wn * wp * wr;
        sum += w * tap.rgb;
        weights += w;
    }
    return sum / weights;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (outside_frame(px)) return;
#ifdef HAS_SPECULAR
    vec3 color = imageLoad(specular_in, px).rgb;
#else
    vec3 color = vec3(0.0);
#endif
    vec4 centre = imageLoad(glossy_in, px);
#ifdef TEMPORAL
    // Only this pixel's: `glossy temporal` read the history before this pass.
    imageStore(glossy_history, px, centre);
#endif
    uvec2 hit;
    Surface s;
    // Material terms and the shading normal are all the albedo needs (no triangle rebuilt).
    if (centre.a > 0.0 && read_primary_material(px, hit, s)) {
        s.normal = oct_decode(texelFetch(gb_normal, px, 0).x);
        vec3 v = -camera_ray_dir(vec2(px) + 0.5);
        float nv = face_viewer(s, v);
        // composite adds env_specular_radiance x albedo: the sum never goes below zero.
        Surface lobe = glossy_lobe(s);
        vec3 env = env_specular_radiance(lobe, v);
        vec3 correction = max(filtered_correction(px, centre, lobe.roughness), -env);
        color += correction * glossy_lobe_albedo(s, v) * s.occlusion;
    }
    imageStore(reflected_out, px, vec4(color, 1.0));
}
