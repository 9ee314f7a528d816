// The one shading path. What is computed at a surface (direct light with
// shadow rays, emission, ambient, mirror reflection, refraction) lives
// here; how a ray finds its hit is the traversal include chosen by the
// variant (trace/query.glsl, ...). Without one (TRACE_NONE) no ray is
// traced. The passes (direct, specular, composite) each use a part of it.
#ifndef INTEGRATOR_GLSL
#define INTEGRATOR_GLSL
#include "scene.glsl"
#include "env.glsl"
#include "brdf.glsl"
#include "fresnel.glsl"
#include "lights.glsl"
#include "offset.glsl"
#include "trace.glsl"
#include "shadow_map.glsl"

// Specialization constants: effects the scene does not need are compiled out.
layout(constant_id = SPEC_SHADOWS) const bool SHADOWS = false;
layout(constant_id = SPEC_REFLECTIONS) const bool REFLECTIONS = false;
layout(constant_id = SPEC_REFRACTIONS) const bool REFRACTIONS = false;
layout(constant_id = SPEC_MAX_DEPTH) const uint MAX_DEPTH = 8u;
layout(constant_id = SPEC_MIN_WEIGHT) const float MIN_WEIGHT = 0.01;
layout(constant_id = SPEC_COUNT_RAYS) const bool COUNT_RAYS = false;

// The rays this pixel traced per effect (EFFECT_BIT_*), for the budget's
// cost model: a ray counts for the effect of the chain it belongs to.
uint g_effect_rays[EFFECT_COUNT] = uint[](0u, 0u, 0u);
uint g_ray_effect = EFFECT_BIT_SHADOWS;

void count_ray(uint kind) {
    if (COUNT_RAYS) atomicAdd(ray_counts[kind], 1u);
    g_effect_rays[g_ray_effect]++;
}

// Adds this pixel's rays per effect to its object's budget statistics
// (only under a budget: nothing else reads them).
void budget_count_rays(uint instance) {
    if ((frame.flags & FRAME_BUDGET) == 0u) return;
    uint base = BUDGET_STAT_WORDS * instances[instance].object_id + BUDGET_STAT_RAYS;
    for (uint e = 0u; e < EFFECT_COUNT; ++e) {
        if (g_effect_rays[e] != 0u) atomicAdd(budget_stats[base + e], g_effect_rays[e]);
    }
}

// MIRROR_ROUGHNESS (generated/shared.glsl): surfaces at most this rough
// are traced as mirrors (glossy-as-mirror).
const float RAY_TMAX = 1e30;

#ifdef TRACE_NONE
bool trace_closest(vec3 o, vec3 d, float tmax, out RayHit hit) { return false; }
vec3 trace_shadow(vec3 o, vec3 d, float tmax) { return vec3(1.0); }
#endif

float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }

// The ray-traced effects (EFFECT_* bits) the primary hit being shaded gets
// (the budget's selection, budget_effects); an effect left out traces no
// ray: exactly the raster-only shading of that effect. A chain, once
// started, is traced whole (specular sets EFFECT_ALL after the primary hit).
uint g_effects = EFFECT_ALL;

bool effect_on(uint bit) {
    return ((g_effects >> bit) & 1u) != 0u;
}

// `--fallback raster`: an effect the budget leaves out is approximated
// without rays instead of left out (render/budget's Fallback).
bool raster_fallback() {
    return (frame.flags & FRAME_FALLBACK_RASTER) != 0u;
}

// Whether `bit` is shaded at all: traced, or its raster fallback.
bool effect_shaded(uint bit) {
    return effect_on(bit) || raster_fallback();
}

// Direct light from every punctual light; with SHADOWS, each light that
// casts shadows is tested with a transmittance ray, or, where the budget
// left the pixel's shadows out under the raster fallback, its shadow map. `gn` is the unit
// geometric normal on the viewer's side.
vec3 direct_light(Surface s, vec3 v, vec3 gn) {
    vec3 c = vec3(0.0);
    for (uint i = 0u; i < frame.light_count; ++i) {
        Light light = lights[i];
        LightSample ls = sample_light(light, s.position);
        vec3 contrib = brdf_eval(s, v, ls.l, ls.irradiance);
        if (SHADOWS && effect_on(EFFECT_BIT_SHADOWS) && (light.flags & LIGHT_CASTS_SHADOWS) != 0u && max3(contrib) > 0.0) {
            bool light_side = dot(gn, ls.l) > 0.0;
            if (!light_side && s.transmission <= 0.0) {
                // A normal map tilted the shading normal towards a light
                // behind the geometry: the surface itself occludes it.
                contrib = vec3(0.0);
            } else {
                vec3 o = offset_ray(s.position, light_side ? gn : -gn, s.extent);
                float tmax = light.type == LIGHT_DIRECTIONAL ? RAY_TMAX : ls.distance * (1.0 - 1e-4);
                count_ray(RAY_KIND_SHADOW);
                contrib *= trace_shadow(o, ls.l, tmax);
            }
        } else if (SHADOWS && raster_fallback() && light.type != LIGHT_POINT && (light.flags & LIGHT_CASTS_SHADOWS) != 0u
                   && max3(contrib) > 0.0) {
            // The shadow bit is off: the shadow map instead (point lights
            // have none and stay unshadowed).
            bool light_side = dot(gn, ls.l) > 0.0;
            if (!light_side && s.transmission <= 0.0) {
                contrib = vec3(0.0);
            } else {
                contrib *= shadow_map_visibility(i, s.position, light_side ? gn : -gn, ls.distance);
            }
        }
        c += contrib;
    }
    return c;
}

// A ray cone (texture LOD): width at the ray's origin and spread angle.
// Reflection and refraction keep the spread (the planar approximation:
// surface curvature is not tracked), so the width grows linearly with the
// total path length, as for a pixel footprint seen in a flat mirror.
struct Cone {
    float width;
    float spread;
};

struct Branch {
    vec3 origin;
    vec3 dir;
    vec3 weight;
    uint depth;
    Cone cone;
    uint effect;  // EFFECT_BIT_* of the chain it belongs to
    // The budget left its effect out (raster fallback): not traced, the
    // environment in its direction stands for whatever it would have hit.
    bool env_only;
};

Branch g_stack[BRANCH_STACK_SIZE];
int g_sp = 0;
// The pixel's tree lost a branch (full stack, or the ray budget ran out).
bool g_truncated = false;

void push_branch(vec3 o, vec3 d, vec3 w, uint depth, Cone cone, uint effect) {
    // Importance cutoff: branches that can change the pixel by less than
    // MIN_WEIGHT of their radiance are not traced.
    if (max3(w) >= MIN_WEIGHT && !any(isnan(d)) && !any(isinf(d)) && dot(d, d) > 0.0) {
        if (g_sp < int(BRANCH_STACK_SIZE)) {
            g_stack[g_sp] = Branch(o, normalize(d), w, depth, cone, effect, !effect_on(effect));
            g_sp++;
        } else {
            g_truncated = true;
        }
    }
}

// Keeps the shading normal on the viewer's side (normal maps at grazing
// angles); returns n.v.
float face_viewer(inout Surface s, vec3 v) {
    float nv = dot(s.normal, v);
    if (nv < 1e-4) {
        s.normal = normalize(s.normal + v * (1e-4 - nv));
        nv = dot(s.normal, v);
    }
    return nv;
}

// Whether `s` spawns a mirror reflection at `depth` (traced, or its
// environment-only fallback).
bool is_mirror(Surface s, uint depth) {
    return REFLECTIONS && effect_shaded(EFFECT_BIT_REFLECTIONS) && depth < MAX_DEPTH && s.roughness <= MIRROR_ROUGHNESS;
}

// Whether `s` spawns a refraction branch at `depth` (traced, or its
// environment-only fallback).
bool is_refracting(Surface s, uint depth) {
    return REFRACTIONS && effect_shaded(EFFECT_BIT_REFRACTIONS) && depth < MAX_DEPTH
        && s.transmission * (1.0 - s.metallic) > 0.0;
}

// Whether `s` spawns any branch at `depth`: decided by its material terms
// alone (push_branches may still drop a branch under MIN_WEIGHT).
bool spawns_branches(Surface s, uint depth) {
    return is_mirror(s, depth) || is_refracting(s, depth);
}

// The ambient term of `s` lit by `radiance`, the radiance a Lambertian
// surface of albedo 1 exits (E / pi): SH irradiance, or PRT in composite.
vec3 ambient_light_from(Surface s, bool mirror, vec3 radiance) {
    vec3 f0 = surface_f0(s);
    vec3 diffuse = (1.0 - s.metallic) * (1.0 - s.transmission) * s.base_color;
    return radiance * s.occlusion * (diffuse * (1.0 - f0) + (mirror ? vec3(0.0) : f0));
}

// Environment light on `s` (the ambient term): the irradiance at its
// normal (env.glsl's ambient_radiance). A mirror's specular share comes from
// its reflection branch instead (traced, or the environment in fallback).
vec3 ambient_light(Surface s, bool mirror) {
    return ambient_light_from(s, mirror, ambient_radiance(s.normal));
}

// Pushes the reflection and refraction branches `s` spawns (weight `w`,
// at `depth`, the ray cone `cone` at s); `nv` from face_viewer.
void push_branches(Surface s, vec3 v, float nv, vec3 gn, bool back_face, vec3 w, uint depth, Cone cone) {
    float tm = s.transmission * (1.0 - s.metallic);
    bool mirror = is_mirror(s, depth);
    bool refract_on = is_refracting(s, depth);
    if (!mirror && !refract_on) return;
    // Dielectric interface for the transmissive part; Schlick for the rest.
    vec3 f0 = surface_f0(s);
    float eta = back_face ? s.ior : 1.0 / max(s.ior, 1e-3);
    float fr = fresnel_dielectric(nv, eta);
    vec3 kr = f_schlick(f0, nv);
    // A chain's rays count for the effect that started it at the primary
    // hit (total internal reflection there is part of the refraction).
    bool root = depth == 0u;
    uint reflect_effect = root ? (mirror ? EFFECT_BIT_REFLECTIONS : EFFECT_BIT_REFRACTIONS) : g_ray_effect;
    uint refract_effect = root ? EFFECT_BIT_REFRACTIONS : g_ray_effect;
    if (mirror || fr >= 1.0) {
        vec3 rw = kr * (1.0 - tm) + vec3(fr * tm);
        if (!mirror) rw = vec3(fr * tm);  // total internal reflection only
        vec3 rd = reflect(-v, s.normal);
        if (dot(rd, gn) <= 0.0) rd = reflect(-v, gn);  // stay above the surface
        push_branch(offset_ray(s.position, gn, s.extent), rd, w * rw, depth + 1u, cone, reflect_effect);
    }
    if (refract_on && fr < 1.0) {
        vec3 td = refract_dir(-v, s.normal, eta);
        if (dot(td, gn) >= 0.0) td = refract_dir(-v, gn, eta);
        push_branch(offset_ray(s.position, -gn, s.extent), td, w * tm * (1.0 - fr) * s.base_color, depth + 1u, cone,
                    refract_effect);
    }
}

// Radiance leaving a secondary hit `s` towards v, times `w`; pushes the
// branches it spawns. The primary hit is split over the direct, specular
// and composite passes instead, which compute the same terms.
vec3 shade(Surface s, vec3 v, vec3 gn, bool back_face, vec3 w, uint depth, Cone cone) {
    float nv = face_viewer(s, v);
    vec3 c = s.emissive + direct_light(s, v, gn) + ambient_light(s, is_mirror(s, depth));
    push_branches(s, v, nv, gn, back_face, w, depth, cone);
    return w * c;
}

// Traces every pending branch to completion, at most RAY_BUDGET_PER_PIXEL
// rays; a cut tree is counted (RAY_COUNTER_TRUNCATED) so the host can warn.
vec3 trace_branches() {
    vec3 radiance = vec3(0.0);
    uint traced = 0u;
    while (g_sp > 0) {
        if (traced == RAY_BUDGET_PER_PIXEL) {
            g_truncated = true;
            break;
        }
        traced++;
        g_sp--;
        Branch b = g_stack[g_sp];
        if (b.env_only) {
            // The fallback: the same weight, no ray (the traced image where
            // the ray would have missed everything).
            traced--;
            radiance += b.weight * environment(b.dir);
            continue;
        }
        g_ray_effect = b.effect;
        RayHit h;
        count_ray(RAY_KIND_SECONDARY);
        g_alpha_cone = vec2(b.cone.width, b.cone.spread);
        g_alpha_dir = b.dir;
        bool hit = trace_closest(b.origin, b.dir, RAY_TMAX, h);
        g_alpha_cone = vec2(0.0);
        if (hit) {
            vec3 gn;
            bool back_face;
            Cone at_hit = Cone(b.cone.width + b.cone.spread * h.t, b.cone.spread);
            Surface s = hit_surface(h, b.origin, b.dir, at_hit.width, gn, back_face);
            // Leaving a mesh from inside: the branch crossed its medium.
            vec3 w = back_face ? b.weight * volume_transmittance(h) : b.weight;
            radiance += shade(s, -b.dir, gn, back_face, w, b.depth, at_hit);
        } else {
            radiance += b.weight * environment(b.dir);
        }
    }
    if (g_truncated) atomicAdd(ray_counts[RAY_COUNTER_TRUNCATED], 1u);
    return radiance;
}

#endif
