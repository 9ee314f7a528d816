// The one shading path for direct, specular and composite; ray traversal comes from the variant's
// trace include (trace/query.glsl, ...), and TRACE_NONE traces nothing.
#ifndef INTEGRATOR_GLSL
#define INTEGRATOR_GLSL
#include "scene.glsl"
#include "env.glsl"
#include "brdf.glsl"
#include "split_sum.glsl"
#include "fresnel.glsl"
#include "lights.glsl"
#include "offset.glsl"
#include "trace.glsl"
#include "shadow_map.glsl"

// Effects the scene does not need are compiled out. The recursion limits and ray counting are frame
// uniforms: a software device compiles a variant for ~10 s, too long to spend on a knob.
layout(constant_id = SPEC_SHADOWS) const bool SHADOWS = false;
layout(constant_id = SPEC_REFLECTIONS) const bool REFLECTIONS = false;
layout(constant_id = SPEC_REFRACTIONS) const bool REFRACTIONS = false;

// Rays per effect (EFFECT_BIT_*) for the budget's cost model; a ray counts for its chain's effect.
uint g_effect_rays[EFFECT_COUNT] = uint[](0u, 0u, 0u);
uint g_ray_effect = EFFECT_BIT_SHADOWS;

void count_ray(uint kind) {
    if ((frame.flags & FRAME_COUNT_RAYS) != 0u) atomicAdd(ray_counts[kind], 1u);
    g_effect_rays[g_ray_effect]++;
}

// Only under a budget: nothing else reads these statistics.
void budget_count_rays(uint instance) {
    if ((frame.flags & FRAME_BUDGET) == 0u) return;
    uint base = BUDGET_STAT_WORDS * instances[instance].object_id + BUDGET_STAT_RAYS;
    for (uint e = 0u; e < EFFECT_COUNT; ++e) {
        if (g_effect_rays[e] != 0u) atomicAdd(budget_stats[base + e], g_effect_rays[e]);
    }
}

// Surfaces at most MIRROR_ROUGHNESS (generated/shared.glsl) rough are traced as mirrors; primary hits
// up to GLOSSY_ROUGHNESS get glossy rays (passes/glossy.glsl).
const float RAY_TMAX = 1e30;

#ifdef TRACE_NONE
bool trace_closest(vec3 o, vec3 d, float tmax, out RayHit hit) { return false; }
vec3 trace_shadow(vec3 o, vec3 d, float tmax) { return vec3(1.0); }
bool trace_ray(vec3 o, vec3 d, float tmax, bool shadow, out RayHit hit, out vec3 tr) {
    tr = vec3(1.0);
    return false;
}
#endif

float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }

// Ray-traced effects (EFFECT_* bits) the budget selected for this primary hit; an effect left out
// shades exactly as raster-only. A started chain is traced whole (specular sets EFFECT_ALL).
uint g_effects = EFFECT_ALL;

bool effect_on(uint bit) {
    return ((g_effects >> bit) & 1u) != 0u;
}

// `--fallback raster`: approximate left-out effects without rays (render/budget's Fallback).
bool raster_fallback() {
    return (frame.flags & FRAME_FALLBACK_RASTER) != 0u;
}

bool effect_shaded(uint bit) {
    return effect_on(bit) || raster_fallback();
}

// One light's term at s (`contrib`) and, with SHADOWS, the transmittance ray it needs (`ray`: o, d,
// tmax), or its shadow map where the budget left the shadows out under the raster fallback. `gn`: unit
// geometric normal on the viewer's side; `ms`: ms_compensation at s.
struct LightTerm {
    vec3 contrib;
    bool ray;
    vec3 o;
    vec3 d;
    float tmax;
};

LightTerm light_term(Surface s, vec3 v, vec3 gn, vec3 ms, uint i) {
    Light light = lights[i];
    LightSample ls = sample_light(light, s.position);
    LightTerm t = LightTerm(brdf_eval_ms(s, v, ls.l, ls.irradiance, ms), false, vec3(0.0), ls.l, 0.0);
    if (SHADOWS && effect_on(EFFECT_BIT_SHADOWS) && (light.flags & LIGHT_CASTS_SHADOWS) != 0u && max3(t.contrib) > 0.0) {
        bool light_side = dot(gn, ls.l) > 0.0;
        if (!light_side && s.transmission <= 0.0) {
            // A normal map tilted the shading normal towards a light behind the geometry.
            t.contrib = vec3(0.0);
        } else {
            t.ray = true;
            t.o = offset_ray(s.position, light_side ? gn : -gn, s.extent);
            t.tmax = light.type == LIGHT_DIRECTIONAL ? RAY_TMAX : ls.distance * (1.0 - 1e-4);
        }
    } else if (SHADOWS && (frame.flags & FRAME_SHADOW_MAPS) != 0u && light.type != LIGHT_POINT && (light.flags & LIGHT_CASTS_SHADOWS) != 0u
               && max3(t.contrib) > 0.0) {
        // Point lights have no shadow map and stay unshadowed.
        bool light_side = dot(gn, ls.l) > 0.0;
        if (!light_side && s.transmission <= 0.0) {
            t.contrib = vec3(0.0);
        } else {
            t.contrib *= shadow_map_visibility(i, s.position, light_side ? gn : -gn, ls.distance);
        }
    }
    return t;
}

vec3 surface_ms(Surface s, vec3 v) {
    return ms_compensation(surface_f0(s), max(dot(s.normal, v), 1e-4), s.roughness);
}

#ifdef EMITTERS_GLSL
// One light sample on the emissive triangles (path/emitters.glsl) as a light term at s, its shadow ray
// stopping short of the emitter; contrib 0 where the sample cannot light s.
LightTerm emitter_term(Surface s, vec3 v, vec3 gn, vec3 ms, inout uint rng) {
    LightTerm t = LightTerm(vec3(0.0), false, vec3(0.0), vec3(0.0, 0.0, 1.0), 0.0);
    EmitterSample es;
    if (!sample_emitter_light(s.position, rng, es) || dot(es.d, gn) <= 0.0) return t;
    t.contrib = brdf_eval_ms(s, v, es.d, es.le / es.pdf, ms);
    // Traced whatever SHADOWS says: a scene lit only by emitters has no punctual shadows to compile.
    t.ray = max3(t.contrib) > 0.0;
    t.o = offset_ray(s.position, gn, s.extent);
    t.d = es.d;
    t.tmax = es.t * (1.0 - 1e-3);
    return t;
}

// With g_direct_emitters, direct_light adds one such sample after the punctual lights (through the
// same shadow ray call site), drawn from g_direct_rng.
bool g_direct_emitters = false;
uint g_direct_rng = 0u;
#endif

// Every light's term at s, shadow rays traced.
vec3 direct_light(Surface s, vec3 v, vec3 gn) {
    vec3 c = vec3(0.0);
    vec3 ms = surface_ms(s, v);
    uint n = frame.light_count;
#ifdef EMITTERS_GLSL
    if (g_direct_emitters) n++;
#endif
    for (uint i = 0u; i < n; ++i) {
#ifdef EMITTERS_GLSL
        LightTerm t = i < frame.light_count ? light_term(s, v, gn, ms, i) : emitter_term(s, v, gn, ms, g_direct_rng);
#else
        LightTerm t = light_term(s, v, gn, ms, i);
#endif
        if (t.ray) {
            count_ray(RAY_KIND_SHADOW);
            t.contrib *= trace_shadow(t.o, t.d, t.tmax);
        }
        c += t.contrib;
    }
    return c;
}

// Ray cone for texture LOD. Reflection and refraction keep the spread (planar approximation, curvature
// ignored), so width grows linearly with path length, as in a flat mirror.
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
    // Budget left its effect out (raster fallback): the environment stands in for the hit.
    bool env_only;
    // A glossy lobe sample (passes/glossy.glsl): a miss brings g_lobe_miss, not the environment along dir.
    bool lobe;
};

vec3 g_lobe_miss = vec3(0.0);

Branch g_stack[BRANCH_STACK_SIZE];
int g_sp = 0;
// Full stack or ray budget ran out.
bool g_truncated = false;

void push_branch(vec3 o, vec3 d, vec3 w, uint depth, Cone cone, uint effect) {
    // Importance cutoff.
    if (max3(w) >= frame.min_weight && !any(isnan(d)) && !any(isinf(d)) && dot(d, d) > 0.0) {
        if (g_sp < int(BRANCH_STACK_SIZE)) {
            g_stack[g_sp] = Branch(o, normalize(d), w, depth, cone, effect, !effect_on(effect), false);
            g_sp++;
        } else {
            g_truncated = true;
        }
    }
}

// Keeps the shading normal (and a coat's) on the viewer's side (normal maps at grazing angles).
float face_viewer(inout Surface s, vec3 v) {
    float nv = dot(s.normal, v);
    if (nv < 1e-4) {
        s.normal = normalize(s.normal + v * (1e-4 - nv));
        nv = dot(s.normal, v);
    }
    float cv = dot(s.clearcoat_normal, v);
    if (s.clearcoat > 0.0 && cv < 1e-4) s.clearcoat_normal = normalize(s.clearcoat_normal + v * (1e-4 - cv));
    return nv;
}

// Traced, or its environment-only fallback.
bool is_mirror(Surface s, uint depth) {
    return REFLECTIONS && effect_shaded(EFFECT_BIT_REFLECTIONS) && depth < frame.max_depth && s.roughness <= MIRROR_ROUGHNESS;
}

// A primary hit whose environment specular the `glossy` pass corrects with a traced lobe sample
// (secondary hits keep the split sum). Not under the raster fallback: that is the split sum alone.
bool glossy_traced(uint depth) {
    return REFLECTIONS && effect_on(EFFECT_BIT_REFLECTIONS) && depth == 0u && frame.max_depth > 0u;
}

// The base's lobe gets the pass's sample (unless a sharper coat takes it: is_coat_glossy).
bool is_glossy(Surface s, uint depth) {
    return glossy_traced(depth) && glossy_range(s.roughness) && !coat_in_glossy_range(s);
}

// A coat's lobe in the glossy range, where the base's is not sampled (split_sum.glsl).
bool is_coat_glossy(Surface s, uint depth) {
    return glossy_traced(depth) && coat_in_glossy_range(s);
}

// A coat smooth enough to be a mirror gets a reflection branch of its own (push_branches); a glossy
// one at a primary hit the `glossy` pass's sample where the base is not glossy (is_coat_glossy).
bool is_coat_mirror(Surface s, uint depth) {
    return REFLECTIONS && effect_shaded(EFFECT_BIT_REFLECTIONS) && depth < frame.max_depth && s.clearcoat > 0.0
        && s.clearcoat_roughness <= MIRROR_ROUGHNESS;
}

// The specular lobes of a primary hit no traced ray samples, which the traced ambient's emitter light
// samples light (passes/ao.glsl; composite.comp): the base's and a coat's.
bool base_lobe_untraced(Surface s) {
    return !(is_mirror(s, 0u) || is_glossy(s, 0u)) && s.roughness > MIRROR_ROUGHNESS;
}

bool coat_lobe_untraced(Surface s) {
    return s.clearcoat > 0.0 && !(is_coat_mirror(s, 0u) || is_coat_glossy(s, 0u))
        && s.clearcoat_roughness > MIRROR_ROUGHNESS;
}

// Their albedo towards v (what their light is stored divided by) and their light from l.
vec3 untraced_specular_albedo(Surface s, vec3 v) {
    return (base_lobe_untraced(s) ? specular_albedo(s, v) : vec3(0.0))
        + (coat_lobe_untraced(s) ? vec3(coat_albedo(s, v)) : vec3(0.0));
}

vec3 untraced_specular(Surface s, vec3 v, vec3 l, vec3 e, vec3 ms) {
    vec3 diffuse, spec, coat;
    brdf_layers(s, v, l, ms, diffuse, spec, coat);
    return ((base_lobe_untraced(s) ? spec : vec3(0.0)) + (coat_lobe_untraced(s) ? coat : vec3(0.0))) * e;
}

bool is_refracting(Surface s, uint depth) {
    return REFRACTIONS && effect_shaded(EFFECT_BIT_REFRACTIONS) && depth < frame.max_depth
        && s.transmission * (1.0 - s.metallic) > 0.0;
}

// By material terms alone; push_branches may still drop one under frame.min_weight.
bool spawns_branches(Surface s, uint depth) {
    return is_mirror(s, depth) || is_coat_mirror(s, depth) || is_refracting(s, depth);
}

// Diffuse: `radiance`, what a Lambertian surface of albedo 1 exits (E / pi: SH irradiance, or PRT or
// the reference in composite). Specular: the split-sum environment (split_sum.glsl), except for a
// mirror, whose reflection branch carries it; a coat's the same way. `v`: towards the viewer, n.v > 0
// (face_viewer). Under a coat the layer gets 1 - coat_weight.
vec3 ambient_diffuse(Surface s, vec3 v, vec3 radiance) {
    vec3 diffuse = (1.0 - s.metallic) * (1.0 - s.transmission) * s.base_color;
    return radiance * diffuse * (1.0 - surface_f0(s)) * (s.occlusion * (1.0 - coat_weight(s, v)));
}

vec3 ambient_specular(Surface s, vec3 v, bool mirror) {
    return mirror ? vec3(0.0) : env_specular(s, v) * s.occlusion;
}

vec3 ambient_coat(Surface s, vec3 v, uint depth) {
    return is_coat_mirror(s, depth) ? vec3(0.0) : coat_env_specular(s, v) * s.occlusion;
}

vec3 ambient_light_from(Surface s, vec3 v, uint depth, vec3 radiance) {
    return ambient_diffuse(s, v, radiance) + ambient_specular(s, v, is_mirror(s, depth)) + ambient_coat(s, v, depth);
}

// The share of a lobe's environment light left by a diffuse visibility `ao` at n.v for roughness r
// (Lagarde & de Rousiers 2014): the lobe narrows with smoothness and grazing views keep more.
vec3 specular_occlusion(vec3 ao, float nv, float roughness) {
    return clamp(pow(vec3(nv) + ao, vec3(exp2(-16.0 * roughness - 1.0))) - 1.0 + ao, 0.0, 1.0);
}

vec3 ambient_light(Surface s, vec3 v, uint depth) {
    return ambient_light_from(s, v, depth, ambient_radiance(s.normal));
}

// `nv` from face_viewer; `cone` is the ray cone at s.
void push_branches(Surface s, vec3 v, float nv, vec3 gn, bool back_face, vec3 w, uint depth, Cone cone) {
    float tm = s.transmission * (1.0 - s.metallic);
    bool mirror = is_mirror(s, depth);
    bool coat_mirror = is_coat_mirror(s, depth);
    bool refract_on = is_refracting(s, depth);
    if (!mirror && !coat_mirror && !refract_on) return;
    // Dielectric interface for the transmissive part; Schlick for the rest; a coat passes 1 - cw on.
    vec3 f0 = surface_f0(s);
    float eta = back_face ? s.ior : 1.0 / max(s.ior, 1e-3);
    float fr = fresnel_dielectric(nv, eta);
    vec3 kr = f_schlick(f0, surface_f90(s), nv);
    float cw = coat_weight(s, v), keep = 1.0 - cw;
    // A chain's rays count for the effect that started it at the primary hit (total internal
    // reflection there counts as refraction).
    bool root = depth == 0u;
    uint reflect_effect = root ? (mirror || coat_mirror ? EFFECT_BIT_REFLECTIONS : EFFECT_BIT_REFRACTIONS) : g_ray_effect;
    uint refract_effect = root ? EFFECT_BIT_REFRACTIONS : g_ray_effect;
    vec3 o = offset_ray(s.position, gn, s.extent);
    vec3 rd = reflect(-v, s.normal);
    if (dot(rd, gn) <= 0.0) rd = reflect(-v, gn);  // stay above the surface
    bool reflects = mirror || fr >= 1.0;
    // Else total internal reflection only.
    vec3 rw = (mirror ? kr * (1.0 - tm) + vec3(fr * tm) : vec3(fr * tm)) * keep;
    if (coat_mirror) {
        vec3 cd = reflect(-v, s.clearcoat_normal);
        if (dot(cd, gn) <= 0.0) cd = reflect(-v, gn);
        // Without a normal map of either layer both reflect along one direction: one ray.
        if (reflects && dot(cd, rd) > 1.0 - 1e-6) {
            rw += vec3(cw);
        } else {
            push_branch(o, cd, w * cw, depth + 1u, cone, reflect_effect);
        }
    }
    if (reflects) push_branch(o, rd, w * rw, depth + 1u, cone, reflect_effect);
    if (refract_on && fr < 1.0) {
        vec3 td = refract_dir(-v, s.normal, eta);
        if (dot(td, gn) >= 0.0) td = refract_dir(-v, gn, eta);
        push_branch(offset_ray(s.position, -gn, s.extent), td, w * tm * (1.0 - fr) * keep * s.base_color,
                    depth + 1u, cone, refract_effect);
    }
}

// At most RAY_BUDGET_PER_PIXEL branch rays; a cut tree is counted (RAY_COUNTER_TRUNCATED) so the host
// can warn. Each hit is shaded in full (secondary hits only: the primary hit is split over the direct,
// specular and composite passes): the emission and ambient terms at once, then one light per
// iteration, its shadow ray traced by the same trace_ray call as the branches, so the shader inlines
// one traversal, not two (lavapipe compiled the specular kernel in 13 s instead of 20).
vec3 trace_branches() {
    vec3 radiance = vec3(0.0);
    uint traced = 0u;
    // The surface hit last, whose lights from `next_light` on are still to come.
    Surface ls;
    vec3 lv = vec3(0.0), lgn = vec3(0.0), lw = vec3(0.0), lms = vec3(0.0);
    uint next_light = frame.light_count;
    while (true) {
        bool shadow = next_light < frame.light_count;
        vec3 o, d;
        float tmax = RAY_TMAX;
        vec3 shadow_w = vec3(0.0);
        Branch b;
        if (shadow) {
            LightTerm t = light_term(ls, lv, lgn, lms, next_light++);
            if (!t.ray) {
                radiance += lw * t.contrib;
                continue;
            }
            count_ray(RAY_KIND_SHADOW);
            o = t.o;
            d = t.d;
            tmax = t.tmax;
            shadow_w = lw * t.contrib;
        } else {
            if (g_sp == 0) break;
            if (traced == RAY_BUDGET_PER_PIXEL) {
                g_truncated = true;
                break;
            }
            traced++;
            g_sp--;
            b = g_stack[g_sp];
            if (b.env_only) {
                // Fallback: the image the traced ray would give if it missed everything.
                traced--;
                radiance += b.weight * environment(b.dir);
                continue;
            }
            g_ray_effect = b.effect;
            count_ray(RAY_KIND_SECONDARY);
            o = b.origin;
            d = b.dir;
            g_alpha_cone = vec2(b.cone.width, b.cone.spread);
            g_alpha_dir = b.dir;
        }
        RayHit h;
        vec3 tr;
        bool hit = trace_ray(o, d, tmax, shadow, h, tr);
        g_alpha_cone = vec2(0.0);
        if (shadow) {
            if (!hit) radiance += shadow_w * tr;
        } else if (hit) {
            vec3 gn;
            bool back_face;
            Cone at_hit = Cone(b.cone.width + b.cone.spread * h.t, b.cone.spread);
            Surface s = hit_surface(h, b.origin, b.dir, at_hit.width, gn, back_face);
            // Leaving a mesh from inside: the branch crossed its medium.
            vec3 w = back_face ? b.weight * volume_transmittance(h) : b.weight;
            vec3 v = -b.dir;
            float nv = face_viewer(s, v);
            radiance += w * (s.emissive + ambient_light(s, v, b.depth));
            push_branches(s, v, nv, gn, back_face, w, b.depth, at_hit);
            ls = s;
            lv = v;
            lgn = gn;
            lw = w;
            lms = surface_ms(s, v);
            next_light = 0u;
        } else {
            radiance += b.weight * (b.lobe ? g_lobe_miss : environment(b.dir));
        }
    }
    if (g_truncated) atomicAdd(ray_counts[RAY_COUNTER_TRUNCATED], 1u);
    return radiance;
}

#endif
