// Pass `glossy`: ray-traced glossy reflections at primary hits rougher than a mirror (MIRROR_ROUGHNESS <
// roughness <= GLOSSY_ROUGHNESS). One reflection ray a pixel, its half vector drawn from GGX's
// distribution of visible normals (Heitz 2018), the hit shaded in full (its own mirror / glass chain
// included). What is written is a correction to the split-sum environment `composite` adds anyway: the
// hit's radiance minus the prefiltered environment of the lobe, and zero where the ray escapes. So an
// unoccluded lobe keeps the deterministic split sum (no noise, no sun fireflies from a 1-sample
// environment lookup), and only occluded parts of the lobe are sampled; `glossy_filter` denoises the
// correction and scales it by the lobe's albedo. Two kernels, as `specular` (render/passes/compacted.rs).
#include "../common/gbuffer_read.glsl"
#include "../common/integrator.glsl"
#include "../common/sampling.glsl"
#include "../common/work_list.glsl"

// rgb: the correction (radiance, before the lobe's albedo); a: the camera ray's distance to the hit,
// 0 where the pixel has no glossy sample (the filter's guide).
layout(set = SET_PASS, binding = GLOSSY_OUT, rgba32f) uniform writeonly image2D glossy_out;

void glossy_select(ivec2 px) {
    uvec2 hit;
    Surface s;
    if (outside_frame(px)) return;
    if (read_primary_material(px, hit, s)) {
        g_effects = budget_effects(hit.x - 1u, px);
        if (is_glossy(s, 0u) || is_coat_glossy(s, 0u)) {
            work_append(px);
            return;
        }
    }
    imageStore(glossy_out, px, vec4(0.0));
}

// The pixel's lobe sample: a stream per pixel (and per frame index in a temporal sequence, whose frames
// `glossy temporal` averages), so a frame is the same on every backend and in both modes.
vec3 glossy_correction(PrimaryHit p, ivec2 px) {
    vec3 v = -p.dir;
    face_viewer(p.s, v);
    // The base's lobe, or a coat's (split_sum.glsl glossy_lobe).
    Surface s = glossy_lobe(p.s);
    vec3 t, b;
    basis_of(s.normal, t, b);
    uint rng = pcg_hash(uint(px.x) + pcg_hash(uint(px.y) + pcg_hash(GLOSSY_SEED + ((frame.flags & FRAME_GLOSSY_TEMPORAL) != 0u ? frame.frame_index : 0u))));
    float u1 = next_random(rng), u2 = next_random(rng);
    vec3 vl = vec3(dot(v, t), dot(v, b), dot(v, s.normal));
    vec3 h = sample_vndf(vl, max(s.roughness * s.roughness, 1e-3), u1, u2);
    vec3 l = reflect(-v, t * h.x + b * h.y + s.normal * h.z);
    // Below the surface: the lobe's masked share, which the split sum's albedo already leaves out.
    if (dot(l, s.normal) <= 0.0 || dot(l, p.gn) <= 0.0) return vec3(0.0);
    // A chain the selection started is traced whole; trace_branches' one call site keeps the
    // (inlined) traversal and shading in the kernel once.
    g_effects = EFFECT_ALL;
    g_lobe_miss = env_specular_radiance(s, v);
    // The lobe widens the cone (texture LOD at the hit): about alpha radians.
    float spread = pixel_spread_angle();
    Cone cone = Cone(spread * distance(frame.camera_pos, s.position), spread + s.roughness * s.roughness);
    g_stack[0] = Branch(offset_ray(s.position, p.gn, s.extent), l, vec3(1.0), 1u, cone, EFFECT_BIT_REFLECTIONS,
                        false, true);
    g_sp = 1;
    return trace_branches() - g_lobe_miss;
}

void glossy_listed(uint i) {
    ivec2 px;
    PrimaryHit p;
    if (!work_item(i, px)) return;
    if (!read_primary(px, p)) {
        imageStore(glossy_out, px, vec4(0.0));
        return;
    }
    g_effects = budget_effects(p.instance, px);
    vec3 c = glossy_correction(p, px);
    imageStore(glossy_out, px, vec4(c, distance(frame.camera_pos, p.s.position)));
    budget_count_rays(p.instance);
}
