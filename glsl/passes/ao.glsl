// Pass `ao`: the diffuse ambient at the primary hit from traced rays (`--ambient traced`). AO_SAMPLES
// cosine-distributed rays a pixel, of unlimited range (an interior's sky is hidden by walls metres away),
// give two estimates the filter (`ao filter`) denoises and combines:
// - visibility: each ray is weighted by the environment's radiance along it (the prefiltered map at
//   AO_WEIGHT_LEVEL), and the share sum(V_i w_i) / sum(w_i) scales the environment's SH irradiance. A
//   ratio estimator: exactly 1 where nothing occludes (open surfaces keep the SH irradiance, noise-free),
//   and a blocked bright sky weighs more than a blocked dark ground.
// - one bounce (FRAME_AO_BOUNCE_*, `--no-indirect` leaves it out): a ray that hits brings the hit's
//   direct light (shadow rays traced, a light sample on the emitters among them) and environment light
//   (one cosine ray from the hit, its SH ambient where that escapes: unshadowed it would bring the sky
//   back through the walls), so the underside of a ball on a sunlit floor is lit by the floor, not by
//   the sky seen through it. Irradiance pi mean(L_i).
// - the emitters' direct light (FRAME_AO_EMITTERS): AO_EMITTER_SAMPLES light samples on the emissive
//   triangles (by power, gpu/emitters.rs) with shadow rays, and the emission the cosine rays hit,
//   combined by multiple importance sampling, so a small lamp is found by its light sample and a wide
//   glowing wall by the cosine rays. Only the diffuse lobe: a rough specular lobe no glossy ray samples
//   gets no emitter light (mirror and glossy rays see emitters as they hit them).
// Glass is an occluder that passes its transmission (one interface, untinted by its depth). One trace
// call site for the rays and their shadow rays: a software device compiles an inlined traversal per site.
#include "../common/gbuffer_read.glsl"
#include "../path/emitters.glsl"
#include "../common/integrator.glsl"
#include "../common/sampling.glsl"

// rgb: the visible share per channel; a: the camera ray's distance to the hit (the filter's guide), 0
// where the pixel has no sample (a miss, or nothing diffuse to shade).
layout(set = SET_PASS, binding = AO_OUT, rgba32f) uniform writeonly image2D ao_out;
// rgb: the irradiance of the bounce and the emitters.
layout(set = SET_PASS, binding = AO_BOUNCE_OUT, rgba32f) uniform writeonly image2D ao_bounce_out;
// rgb: the emitters' light on a specular lobe no glossy ray samples, over the lobe's albedo.
#ifdef AO_EMITTER_SPECULAR
layout(set = SET_PASS, binding = AO_SPECULAR_OUT, rgba32f) uniform writeonly image2D ao_specular_out;
#endif

// The smoothed environment along d (the prefiltered chain's level AO_WEIGHT_LEVEL), floored so a black
// channel keeps a defined ratio; 1 where the ambient is one constant.
vec3 ao_weight(vec3 d) {
    if (frame.has_env_map == 0u || (frame.flags & FRAME_AMBIENT_SH) == 0u) return vec3(1.0);
    vec3 w = textureLod(env_specular_map, env_uv(d), float(AO_WEIGHT_LEVEL)).rgb;
    return max(w, vec3(1e-6 * max3(w) + 1e-30));
}

// Ray i of pixel px about the basis (t, b, n). Interleaved sampling (Keller & Heidrich 2001): the
// AO_SAMPLES rays of the 16 pixels of a 4x4 tile fill the cells of one stratified grid over the
// hemisphere (AO_GRID strata in u1 and in azimuth, each cell once, jittered), and each pixel's own rays
// span u1 and turn in azimuth; so the filter, averaging neighbours, averages a stratified set.
vec3 ao_direction(uint i, ivec2 px, vec3 t, vec3 b, vec3 n, inout uint rng) {
    uint k = uint(px.x & 3) + 4u * uint(px.y & 3);
    uint g = i * 16u + k;
    float u1 = (float(g / AO_GRID) + next_random(rng)) / float(AO_GRID);
    float phi = 2.0 * PI * (float((k + 3u * i) % AO_GRID) + next_random(rng)) / float(AO_GRID);
    float r = sqrt(u1);
    return normalize(t * (r * cos(phi)) + b * (r * sin(phi)) + n * sqrt(max(1.0 - u1, 0.0)));
}

// The power heuristic's weight for a strategy of pdf `a` taking n_a samples against one of pdf `b`
// taking n_b (Veach 1997).
float ao_mis(float a, float n_a, float b, float n_b) {
    float x = a * n_a, y = b * n_b;
    return x * x / max(x * x + y * y, 1e-30);
}

// The visible share at p (returned), the irradiance that the bounce and the emitters bring, and the
// radiance the emitters' light samples reflect on the specular lobes no traced ray samples
// (integrator.glsl untraced_specular; seen from v = -p.dir, faced to the viewer).
vec3 ao_estimate(PrimaryHit p, ivec2 px, out vec3 bounce, out vec3 specular) {
    uint rng = pcg_hash(uint(px.x) + pcg_hash(uint(px.y) + pcg_hash(AO_SEED)));
    bool lights = (frame.flags & FRAME_AO_BOUNCE_LIGHTS) != 0u;
    bool sky_bounce = (frame.flags & FRAME_AO_BOUNCE_SKY) != 0u;
    bool emitters_on = (frame.flags & FRAME_AO_EMITTERS) != 0u && emitter_count() > 0u;
    bool bounces = lights || sky_bounce || emitters_on;
    vec3 t, b;
    basis_of(p.s.normal, t, b);
    vec3 o = offset_ray(p.s.position, p.gn, p.s.extent);
    vec3 seen = vec3(0.0), total = vec3(0.0), emitted = vec3(0.0);
    bounce = vec3(0.0);
    specular = vec3(0.0);
    vec3 v = -p.dir, ms = surface_ms(p.s, v);
    // A lobe sharp enough to be a mirror is left out even untraced (`--no-reflections`): one light sample
    // cannot find its highlight.
    bool spec_lobe = base_lobe_untraced(p.s) || coat_lobe_untraced(p.s);
    // The surface a ray hit, whose light stages from `next_light` on are still to come (its lights,
    // then at env_stage its environment ray, at emit_stage a light sample on the emitters), and the
    // hit's weight.
    Surface hs;
    vec3 hv = vec3(0.0), hgn = vec3(0.0), hms = vec3(0.0), hw = vec3(0.0);
    uint env_stage = frame.light_count, emit_stage = env_stage + 1u, done = emit_stage + 1u;
    uint next_light = done, i = 0u, n_emit = 0u;
    while (true) {
        bool shadow = next_light < done, light_sample = false, hit_light_sample = false;
        vec3 ro = o, rd, light = vec3(0.0), w = vec3(0.0), spec_light = vec3(0.0);
        float tmax = RAY_TMAX, mis = 1.0;
        if (shadow && next_light == env_stage) {
            // The environment's light at the hit: one cosine ray about its normal, the hit's SH ambient
            // where it escapes.
            next_light = emit_stage;
            if (!sky_bounce) continue;
            rd = cosine_direction(hs.normal, rng);
            if (dot(rd, hgn) <= 0.0) continue;
            count_ray(RAY_KIND_SHADOW);
            ro = offset_ray(hs.position, hgn, hs.extent);
            light = hw * ambient_diffuse(hs, hv, ambient_radiance(hs.normal));
        } else if (shadow && next_light == emit_stage) {
            // The emitters' light at the hit (part of its direct light; sampled below): the hit's BSDF
            // is not sampled on, so the light sample takes the whole weight.
            next_light = done;
            if (!(lights && emitters_on)) continue;
            hit_light_sample = true;
        } else if (shadow) {
            LightTerm lt = light_term(hs, hv, hgn, hms, next_light++);
            if (!lt.ray) {
                bounce += hw * lt.contrib;
                continue;
            }
            count_ray(RAY_KIND_SHADOW);
            ro = lt.o;
            rd = lt.d;
            tmax = lt.tmax;
            light = hw * lt.contrib;
        } else if (i < AO_SAMPLES) {
            rd = ao_direction(i++, px, t, b, p.s.normal, rng);
            w = ao_weight(rd);
            total += w;
            // Below the geometry (a normal map tilted the lobe): self-occluded, as in direct_light.
            if (dot(rd, p.gn) <= 0.0) continue;
            count_ray(RAY_KIND_SECONDARY);
        } else if (emitters_on && n_emit < AO_EMITTER_SAMPLES) {
            // The emitters' direct light: a light sample, MIS-weighted against the cosine rays that hit
            // them (below).
            n_emit++;
            light_sample = true;
        } else {
            break;
        }
        if (light_sample || hit_light_sample) {
            // One light-sample call site for the primary hit's and the ray hit's: a software device
            // compiles the emission lookup inlined per site.
            EmitterSample es;
            vec3 at = light_sample ? p.s.position : hs.position, agn = light_sample ? p.gn : hgn;
            if (!sample_emitter_light(at, rng, es) || dot(es.d, agn) <= 0.0) continue;
            rd = es.d;
            tmax = es.t * (1.0 - 1e-3);
            if (light_sample) {
                float cos_s = dot(p.s.normal, es.d);
                if (cos_s <= 0.0) continue;
                light = es.le * (cos_s / es.pdf);
                // Only the diffuse lobe is sampled by the cosine rays: the specular one has the light
                // sample alone.
                if (spec_lobe) spec_light = untraced_specular(p.s, v, es.d, es.le / es.pdf, ms);
                mis = ao_mis(es.pdf, float(AO_EMITTER_SAMPLES), cos_s / PI, float(AO_SAMPLES));
            } else {
                ro = offset_ray(hs.position, hgn, hs.extent);
                light = hw * brdf_eval_ms(hs, hv, es.d, es.le / es.pdf, hms);
                if (!(max3(light) > 0.0)) continue;
            }
            count_ray(RAY_KIND_SHADOW);
        }
        RayHit h;
        vec3 tr;
        // Without the bounce a visibility ray is a shadow ray: any hit, glass passing its transmittance.
        bool hit = trace_ray(ro, rd, tmax, shadow || light_sample || !bounces, h, tr);
        if (shadow) {
            if (!hit) bounce += light * tr;
        } else if (light_sample) {
            // The cosine rays stop at glass: an emitter seen through it comes by light samples alone.
            if (!hit) {
                emitted += light * tr * (all(equal(tr, vec3(1.0))) ? mis : 1.0);
                specular += spec_light * tr;
            }
        } else if (!hit) {
            seen += w * tr;
        } else if (bounces) {
            vec3 gn;
            bool back_face;
            hs = hit_surface(h, ro, rd, 0.0, gn, back_face);
            float passes = hs.transmission * (1.0 - hs.metallic);
            seen += w * passes;
            hv = -rd;
            face_viewer(hs, hv);
            hgn = gn;
            hms = surface_ms(hs, hv);
            hw = vec3(1.0 - passes);
            if (emitters_on && max3(hs.emissive) > 0.0) {
                float pdf_light = emitter_hit_pdf(h, rd);
                float cos_s = max(dot(p.s.normal, rd), 0.0);
                bounce += hw * hs.emissive * ao_mis(cos_s / PI, float(AO_SAMPLES), pdf_light, float(AO_EMITTER_SAMPLES));
            }
            // Nothing to bounce where the hit passes all light on (clear glass): its stages are
            // skipped, drawing no random numbers, so an IOR-1 slab leaves the pixel's samples as they are.
            next_light = max3(hw) > 0.0 ? (lights ? 0u : env_stage) : done;
        }
    }
    // Cosine-weighted rays: irradiance is pi times the mean radiance; a light sample's estimate is
    // already irradiance.
    bounce = bounce * (PI / float(AO_SAMPLES)) + emitted / float(AO_EMITTER_SAMPLES);
    specular /= float(AO_EMITTER_SAMPLES);
    return seen / total;
}

// Surfaces whose ambient the estimate scales: anything with a diffuse part, or an environment
// specular no traced ray corrects (mirrors and glossy lobes are traced; composite.comp).
bool ao_shades(Surface s) {
    bool diffuse = (1.0 - s.metallic) * (1.0 - s.transmission) * max3(s.base_color) > 0.0;
    return diffuse || !(is_mirror(s, 0u) || is_glossy(s, 0u)) || coat_lobe_untraced(s);
}

void ao_pixel(ivec2 px) {
    PrimaryHit p;
    if (outside_frame(px)) return;
    if (!read_primary(px, p) || !ao_shades(p.s)) {
        imageStore(ao_out, px, vec4(1.0, 1.0, 1.0, 0.0));
        imageStore(ao_bounce_out, px, vec4(0.0));
#ifdef AO_EMITTER_SPECULAR
        imageStore(ao_specular_out, px, vec4(0.0));
#endif
        return;
    }
    face_viewer(p.s, -p.dir);
    vec3 bounce, specular;
    vec3 share = ao_estimate(p, px, bounce, specular);
    if (any(isnan(bounce)) || any(isinf(bounce))) bounce = vec3(0.0);
    imageStore(ao_out, px, vec4(share, distance(frame.camera_pos, p.s.position)));
    imageStore(ao_bounce_out, px, vec4(bounce, 0.0));
#ifdef AO_EMITTER_SPECULAR
    specular /= max(untraced_specular_albedo(p.s, -p.dir), vec3(1e-4));
    if (any(isnan(specular)) || any(isinf(specular))) specular = vec3(0.0);
    imageStore(ao_specular_out, px, vec4(specular, 0.0));
#endif
}
