// Pass `terms` (report/attribution.rs): for each term in Frame.accum_bounces (TERM_*), the path-traced
// light it carries to the primary hit (minus the hybrid's direct light through glass for the caustics);
// `composite` (variant TERMS) leaves out its own ambient terms the selection covers and adds this, so
// it shows the hybrid with those terms from the path tracer. Each sample takes one lobe of
// path/bsdf.glsl, chosen by albedo (diffuse cosine, or GGX visible normals, Heitz 2018); the hit decides:
// - miss: TERM_ENV_SPECULAR via the specular lobe of a non-mirror (replaces the split-sum environment),
//   TERM_VISIBILITY via the diffuse lobe (replaces the diffuse SH/PRT ambient).
// - rough opaque surface: TERM_INDIRECT (one bounce, lit by punctual lights and a light sample on the
//   emitters, glass opaque); its emission TERM_EMITTERS (replaces the hybrid's emitter light: its light
//   samples and the traced ambient's rays that hit emitters).
// - glass or a perfectly smooth surface: TERM_CAUSTICS, a chain of at most TERMS_CHAIN BSDF samples;
//   replaces the hybrid's direct light through glass (its shadow rays pass transmissive occluders).
// Each term is a set of the truth's own paths, so supplying one never adds light the truth lacks;
// what no term holds is the residual. Seeded by pixel and Frame.accum_frame so every backend traces the
// same rays. One trace and one shade call site each: a software device compiles every inlined
// traversal (lavapipe took 12 minutes for a version with six).
#include "../common/gbuffer_read.glsl"
#include "../path/emitters.glsl"
#include "../common/integrator.glsl"
#include "../path/bsdf.glsl"

layout(set = SET_PASS, binding = TERMS_OUT, rgba32f) uniform image2D terms_accum;
layout(set = SET_PASS, binding = DIRECT_IN, rgba32f) uniform readonly image2D direct_in;

bool term_on(uint bit) {
    return (frame.accum_bounces & bit) != 0u;
}

// Light a path continues through: glass, or a perfectly smooth surface.
bool passes_light_on(Surface s) {
    return s.transmission * (1.0 - s.metallic) > 0.0 || s.roughness * s.roughness < DELTA_ALPHA;
}

// A surface to light by the punctual lights, times weight.
struct Shading {
    Surface s;
    vec3 v, gn;
    vec3 weight;
    bool opaque;   // shadow rays blocked by glass (g_opaque_occluders)
};

// Returns emission and environment light; `end` is the surface to shade (`end.weight` 0: none).
vec3 terms_path(PrimaryHit p, Bsdf m, vec3 v, bool mirror, inout uint rng, out Shading end) {
    end.weight = vec3(0.0);
    // No specular lobe where the hybrid traces a mirror itself.
    uint beyond = TERM_VISIBILITY | TERM_INDIRECT | TERM_EMITTERS | TERM_CAUSTICS;
    float pd = term_on(beyond) ? m.p_diff : 0.0;
    float ps = !mirror && term_on(beyond | TERM_ENV_SPECULAR) ? m.p_spec : 0.0;
    if (pd + ps <= 0.0) return vec3(0.0);
    bool diffuse = next_random(rng) * (pd + ps) < pd;
    float u1 = next_random(rng), u2 = next_random(rng);
    vec3 l, w;
    if (diffuse) {
        float r = sqrt(u1), phi = 2.0 * PI * u2;
        l = vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u1, 0.0)));
        // Lambert weighted by 1 - F, as bsdf_eval: f cos / (cos / pi).
        w = (1.0 - f_schlick(m.f0, m.f90, max(dot(v, normalize(v + l)), 0.0))) * m.diffuse * ((pd + ps) / pd);
    } else if (m.delta) {
        l = vec3(-v.x, -v.y, v.z);
        w = m.spec_w * f_schlick(m.f0, m.f90, max(v.z, 1e-4)) * ((pd + ps) / ps);
    } else {
        vec3 h = sample_vndf(v, m.alpha, u1, u2);
        l = reflect(-v, h);
        if (l.z <= 0.0) return vec3(0.0);
        float a2 = m.alpha * m.alpha, lv = ggx_lambda(max(v.z, 1e-4), a2);
        // f cos / pdf = F G2 / G1 (height-correlated Smith).
        float g = (1.0 + lv) / (1.0 + lv + ggx_lambda(l.z, a2));
        w = m.spec_w * m.ms * f_schlick(m.f0, m.f90, max(dot(v, h), 0.0)) * g * ((pd + ps) / ps);
    }
    vec3 d = normalize(bsdf_world(m, l));
    if (dot(d, p.gn) <= 0.0) return vec3(0.0);  // below the geometry: occluded
    uint miss_term = diffuse ? TERM_VISIBILITY : TERM_ENV_SPECULAR;
    vec3 o = offset_ray(p.s.position, p.gn, p.s.extent);
    vec3 radiance = vec3(0.0);
    // The primary hit's ray, then (caustics) up to TERMS_CHAIN more through glass and smooth surfaces.
    for (uint k = 0u; k <= TERMS_CHAIN; ++k) {
        bool first = k == 0u;
        RayHit h;
        count_ray(RAY_KIND_SECONDARY);
        if (!trace_closest(o, d, RAY_TMAX, h)) {
            if (term_on(first ? miss_term : TERM_CAUSTICS)) radiance += w * environment(d);
            break;
        }
        vec3 gn;
        bool back_face;
        Surface s = hit_surface(h, o, d, 0.0, gn, back_face);
        if (back_face) w *= volume_transmittance(h);  // crossed a medium
        if (term_on(first ? TERM_EMITTERS : TERM_CAUSTICS)) radiance += w * s.emissive;
        if (!passes_light_on(s)) {
            if (term_on(first ? TERM_INDIRECT : TERM_CAUSTICS)) end = Shading(s, -d, gn, w, true);
            break;
        }
        if (!term_on(TERM_CAUSTICS)) break;
        vec3 v_world = -d;
        face_viewer(s, v_world);
        Bsdf mb = bsdf_at(s, v_world, back_face);
        BsdfSample bs;
        if (!bsdf_sample(mb, bsdf_local(mb, v_world), rng, bs)) break;
        d = normalize(bsdf_world(mb, bs.l));
        if ((dot(d, gn) > 0.0) != (bs.l.z > 0.0)) break;  // leaked through the geometry
        w *= bs.weight;
        if (!(max3(w) > 0.0) || any(isinf(w))) break;  // also NaN
        o = offset_ray(s.position, bs.l.z > 0.0 ? gn : -gn, s.extent);
    }
    return radiance;
}

void terms_pixel(ivec2 px) {
    PrimaryHit p;
    if (outside_frame(px) || !read_primary(px, p)) return;
    vec3 v_world = -p.dir;
    face_viewer(p.s, v_world);
    g_effects = budget_effects(p.instance, px);
    bool mirror = is_mirror(p.s, 0u);
    Bsdf m = bsdf_at(p.s, v_world, p.back_face);
    vec3 v = bsdf_local(m, v_world);
    uint rng = pcg_hash(uint(px.x) + pcg_hash(uint(px.y) + pcg_hash(frame.accum_frame ^ 0x7f4a7c15u)));
    float n = float(TERMS_SAMPLES_PER_FRAME);
    vec3 sum = vec3(0.0);
    // Iteration 0 shades direct light with glass opaque: minus `direct`'s (glass transmits), that is the
    // hybrid's light through glass, which the caustics replace.
    for (uint i = 0u; i <= TERMS_SAMPLES_PER_FRAME; ++i) {
        Shading end;
        vec3 c = vec3(0.0);
        if (i == 0u) {
            end = Shading(p.s, v_world, p.gn, vec3(term_on(TERM_CAUSTICS) ? n : 0.0), true);
            if (term_on(TERM_CAUSTICS)) c -= n * imageLoad(direct_in, px).rgb;
        } else {
            c = terms_path(p, m, v, mirror, rng, end);
        }
        if (max3(end.weight) > 0.0) {
            g_opaque_occluders = end.opaque;
            face_viewer(end.s, end.v);
            // A bounce's end is lit by the emitters too (as the hybrid's bounce is); the primary hit's
            // own emitter light is the hybrid's (`ao`).
            g_direct_emitters = i != 0u;
            g_direct_rng = rng;
            c += end.weight * direct_light(end.s, end.v, end.gn);
            rng = g_direct_rng;
            g_opaque_occluders = false;
        }
        if (any(isnan(c)) || any(isinf(c))) c = vec3(0.0);
        sum += c;
    }
    vec4 acc = vec4(sum, n);
    if (frame.accum_frame != 0u) acc += imageLoad(terms_accum, px);
    imageStore(terms_accum, px, acc);
}
