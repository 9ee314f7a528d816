// Split-sum environment specular (Karis 2013) and GGX multiple-scattering compensation (Turquin 2019),
// from the host's tables (gpu/split_sum.rs, gpu/env_prefilter.rs).
#ifndef SPLIT_SUM_GLSL
#define SPLIT_SUM_GLSL
#include "scene.glsl"
#include "env.glsl"
#include "brdf.glsl"

// (A, B): the GGX lobe's directional albedo at n.v is f0 A + f90 B.
vec2 dfg_at(float nv, float roughness) {
    return textureLod(dfg_table, vec2(clamp(nv, 0.0, 1.0), clamp(roughness, 0.0, 1.0)), 0.0).rg;
}

// 1 + f0 (1 / E - 1), E the lobe's albedo at f0 = f90 = 1: scales a single-scattering lobe up to the
// energy the lobe's multiple scattering returns.
vec3 ms_from(vec3 f0, vec2 ab) {
    return 1.0 + f0 * (1.0 / max(ab.x + ab.y, 1e-3) - 1.0);
}

vec3 ms_compensation(vec3 f0, float nv, float roughness) {
    return ms_from(f0, dfg_at(nv, roughness));
}

// The unshadowed environment's radiance over the surface's GGX lobe towards v: the prefiltered map
// about the lobe's dominant direction (towards n as roughness grows; Filament). Constant ambient modes
// reflect the constant. What a glossy ray that misses stands for (passes/glossy.glsl).
vec3 env_specular_radiance(Surface s, vec3 v) {
    if (frame.has_env_map == 0u || (frame.flags & (FRAME_AMBIENT_SH | FRAME_AMBIENT_PRT)) == 0u) {
        return frame.env_ambient;
    }
    float a = s.roughness * s.roughness;
    vec3 r = normalize(mix(reflect(-v, s.normal), s.normal, a * a));
    float lod = s.roughness * float(ENV_SPECULAR_LEVELS - 1u);
    return textureLod(env_specular_map, env_uv(r), lod).rgb * frame.env_intensity;
}

// The GGX lobe's albedo towards v (n.v floored at 1e-4), multiple scattering included: what scales the
// radiance it reflects. Under a coat, the share the coat lets through.
vec3 specular_albedo(Surface s, vec3 v) {
    vec3 f0 = surface_f0(s);
    vec2 ab = dfg_at(max(dot(s.normal, v), 1e-4), s.roughness);
    return (f0 * ab.x + surface_f90(s) * ab.y) * ms_from(f0, ab) * (1.0 - coat_weight(s, v));
}

// The surface's GGX lobe lit by the unshadowed environment (the coat's apart: coat_env_specular).
vec3 env_specular(Surface s, vec3 v) {
    return env_specular_radiance(s, v) * specular_albedo(s, v);
}

// The coat's lobe albedo towards v, its weight applied; single scattering, as brdf_lobes' coat.
float coat_albedo(Surface s, vec3 v) {
    vec2 ab = dfg_at(max(dot(s.clearcoat_normal, v), 1e-4), s.clearcoat_roughness);
    return s.clearcoat * (COAT_F0 * ab.x + ab.y);
}

// The coat's lobe lit by the unshadowed environment.
vec3 coat_env_specular(Surface s, vec3 v) {
    if (s.clearcoat <= 0.0) return vec3(0.0);
    return env_specular_radiance(coat_layer(s), v) * coat_albedo(s, v);
}

// Roughness between a mirror's and GLOSSY_ROUGHNESS: the `glossy` pass samples such a lobe at primary
// hits, one a pixel: a coat's where the base's is not in the range or is rougher (the sharper lobe,
// which the split sum's occlusion estimate serves worse), else the base's.
bool glossy_range(float roughness) {
    return roughness > MIRROR_ROUGHNESS && roughness <= GLOSSY_ROUGHNESS;
}

bool coat_in_glossy_range(Surface s) {
    return s.clearcoat > 0.0 && glossy_range(s.clearcoat_roughness)
        && (!glossy_range(s.roughness) || s.clearcoat_roughness < s.roughness);
}

// The lobe a listed pixel's glossy sample is drawn from (its normal and roughness), and its albedo.
Surface glossy_lobe(Surface s) {
    return coat_in_glossy_range(s) ? coat_layer(s) : s;
}

vec3 glossy_lobe_albedo(Surface s, vec3 v) {
    return coat_in_glossy_range(s) ? vec3(coat_albedo(s, v)) : specular_albedo(s, v);
}

#endif
