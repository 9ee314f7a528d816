#version 460
// Pass `composite`: emission + direct light (`direct`) + ambient + the traced specular chain (variant
// HAS_SPECULAR; a budget's partial share filled in, common/budget_fill.glsl); the environment on a miss. Variant REFERENCE takes the ambient from `reference`'s
// accumulation; AO scales it by the traced visibility (`ao filter`); TERMS replaces the ambient terms
// `terms` supplies (the report's attribution); DEBUG_VIEWS shows a G-buffer view and reads neither
// light pass.
#include "common/gbuffer_read.glsl"
#include "common/integrator.glsl"
#include "common/prt.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
#ifndef DEBUG_VIEWS
layout(set = SET_PASS, binding = DIRECT_IN, rgba32f) uniform readonly image2D direct_in;
#endif
#ifdef HAS_SPECULAR
layout(set = SET_PASS, binding = SPECULAR_IN, rgba32f) uniform readonly image2D specular_in;
#include "common/budget_fill.glsl"
#endif
#ifdef TERMS
layout(set = SET_PASS, binding = TERMS_IN, rgba32f) uniform readonly image2D terms_in;
#endif
#ifdef REFERENCE
layout(set = SET_PASS, binding = REFERENCE_IN, rgba32f) uniform readonly image2D reference_in;
#endif
#ifdef AO
layout(set = SET_PASS, binding = AO_VISIBILITY_IN, rgba32f) uniform readonly image2D ao_visibility;
#ifdef AO_EMITTER_SPECULAR
layout(set = SET_PASS, binding = AO_EMITTER_SPECULAR_IN, rgba32f) uniform readonly image2D emitter_specular;
#endif
#endif
layout(set = SET_PASS, binding = HDR_OUT, rgba32f) uniform writeonly image2D hdr_out;

vec3 hash_color(uint x) {
    x = (x ^ 61u) ^ (x >> 16u);
    x *= 9u;
    x = x ^ (x >> 4u);
    x *= 0x27d4eb2du;
    x = x ^ (x >> 15u);
    return vec3(x & 255u, (x >> 8u) & 255u, (x >> 16u) & 255u) / 255.0;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (outside_frame(px)) return;
    PrimaryHit p;
    if (!read_primary(px, p)) {
        vec3 bg = frame.debug_view == DEBUG_NONE ? environment(p.dir) : vec3(0.0);
        imageStore(hdr_out, px, vec4(bg, 1.0));
        return;
    }
    Surface s = p.s;
    vec3 color = vec3(0.0);
#ifdef DEBUG_VIEWS
    switch (frame.debug_view) {
    case DEBUG_ALBEDO: color = s.base_color; break;
    case DEBUG_NORMAL: color = s.normal * 0.5 + 0.5; break;
    // Reversed-Z depth (znear / view distance), shown on a log scale.
    case DEBUG_DEPTH: {
        vec3 forward = -transpose(mat3(frame.view))[2];
        float depth = frame.znear / max(dot(s.position - frame.camera_pos, forward), 1e-30);
        color = vec3(clamp(1.0 + log2(max(depth, 1e-8)) / 16.0, 0.0, 1.0));
        break;
    }
    case DEBUG_MATERIAL: color = vec3(s.metallic, s.roughness, s.transmission); break;
    case DEBUG_OBJECT: color = hash_color(instances[p.instance].object_id + 1u); break;
    case DEBUG_OBJECT_ID: color = vec3(float(instances[p.instance].object_id + 1u)); break;
    case DEBUG_SELECTION: {
        float grey = dot(s.base_color, vec3(0.2126, 0.7152, 0.0722));
        // Paper mode's Figure 2: red = every effect traced; per effect
        // (effects mode) red = shadows, green = reflections, blue =
        // refractions; grey = raster only.
        uint e = budget_effects(p.instance, px);
        vec3 bits = vec3(e & 1u, (e >> 1u) & 1u, (e >> 2u) & 1u);
        if (e == EFFECT_ALL) bits = vec3(1.0, 0.0, 0.0);
        color = e == 0u ? vec3(0.5 * grey + 0.1) : mix(vec3(0.1), vec3(0.25 + 0.75 * grey), bits);
        break;
    }
    }
#else
    g_effects = budget_effects(p.instance, px);
    vec3 v = -p.dir;
    face_viewer(s, v);
#ifdef HAS_SPECULAR
    vec3 specular = imageLoad(specular_in, px).rgb;
    // A partial pair's untraced pixel shades as traced, from its traced neighbours.
    uint missing = budget_partial_missing(p.instance, px);
    vec3 filled;
    if (missing != 0u && budget_fill(px, p, filled)) {
        specular = filled;
        g_effects |= missing;
    }
#endif
    bool mirror = is_mirror(s, 0u);
#ifdef REFERENCE
    // The ray-traced reference replaces the ambient radiance.
    vec4 acc = imageLoad(reference_in, px);
    vec3 radiance = acc.rgb / max(acc.a, 1.0);
#else
    // Diffuse PRT on static geometry (FRAME_AMBIENT_PRT), else SH/constant.
    vec3 prt_e;
    vec3 radiance = prt_irradiance(p.instance, p.primitive, p.b, prt_e) ? prt_e / PI : ambient_radiance(s.normal);
#endif
    vec3 diffuse = ambient_diffuse(s, v, radiance);
    vec3 glossy = ambient_specular(s, v, mirror);
    // A coat's environment lobe (the `glossy` pass corrects a glossy one where the base is not glossy;
    // no attribution term covers it).
    vec3 coat = ambient_coat(s, v, 0u);
#ifdef AO
    // The traced ambient (`ao filter`): its radiance, and its visible share as the specular occlusion of
    // a lobe no glossy ray corrects (with the attribution terms the `glossy` pass does not run).
    vec4 traced = imageLoad(ao_visibility, px);
    diffuse = ambient_diffuse(s, v, traced.rgb);
#ifdef TERMS
    bool coat_corrected = false;
#else
    bool coat_corrected = is_coat_glossy(s, 0u);
#endif
    // Its occlusion from the visibility sampled about the base's normal.
    if (!coat_corrected) {
        coat *= specular_occlusion(vec3(traced.a), max(dot(s.clearcoat_normal, v), 1e-4), s.clearcoat_roughness);
    }
#ifdef TERMS
    bool corrected = false;
#else
    bool corrected = is_glossy(s, 0u);
#endif
    if (!corrected) {
        float nv = max(dot(s.normal, v), 1e-4);
        glossy *= specular_occlusion(vec3(traced.a), nv, s.roughness);
        // The emitters on the lobe (their light samples' shadow rays traced: not occluded again).
#ifdef AO_EMITTER_SPECULAR
        glossy += imageLoad(emitter_specular, px).rgb * untraced_specular_albedo(s, v) * s.occlusion;
#endif
    }
#endif
#ifdef TERMS
    // The path tracer's terms (`terms`) replace the ambient they cover (the traced ambient's parts:
    // FRAME_AO_* flags, cleared by the host).
#ifndef AO
    if ((frame.accum_bounces & TERM_VISIBILITY) != 0u) diffuse = vec3(0.0);
#endif
    if ((frame.accum_bounces & TERM_ENV_SPECULAR) != 0u) glossy = vec3(0.0);
#endif
    color = primary_emissive(px, p.instance, p.primitive, p.b) + imageLoad(direct_in, px).rgb + diffuse + glossy + coat;
#ifdef HAS_SPECULAR
    color += specular;
#endif
#ifdef TERMS
    // Noise in a term can take a dark pixel below zero.
    vec4 terms = imageLoad(terms_in, px);
    color = max(color + terms.rgb / max(terms.a, 1.0), vec3(0.0));
#endif
#endif
    imageStore(hdr_out, px, vec4(color, 1.0));
}
