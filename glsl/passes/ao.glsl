// Pass `ao`: the diffuse ambient at the primary hit from traced rays (`--ambient traced`). AO_SAMPLES
// cosine-distributed rays a pixel, of unlimited range (an interior's sky is hidden by walls metres away),
// give two estimates the filter (`ao filter`) denoises and combines:
// - visibility: each ray is weighted by the environment's radiance along it (the prefiltered map at
//   AO_WEIGHT_LEVEL), and the share sum(V_i w_i) / sum(w_i) scales the environment's SH irradiance. A
//   ratio estimator: exactly 1 where nothing occludes (open surfaces keep the SH irradiance, noise-free),
//   and a blocked bright sky weighs more than a blocked dark ground.
// - one bounce (FRAME_AO_BOUNCE_*, `--no-indirect` leaves it out): a ray that hits brings the hit's
//   emission, direct light (shadow rays traced) and environment light (one cosine ray from the hit, its
//   SH ambient where that escapes: unshadowed it would bring the sky back through the walls), so the
//   underside of a ball on a sunlit floor is lit by the floor, not by the sky seen through it.
//   Irradiance pi mean(L_i).
// Glass is an occluder that passes its transmission (one interface, untinted by its depth). One trace
// call site for the rays and their shadow rays: a software device compiles an inlined traversal per site.
#include "../common/gbuffer_read.glsl"
#include "../common/integrator.glsl"
#include "../common/sampling.glsl"

// rgb: the visible share per channel; a: the camera ray's distance to the hit (the filter's guide), 0
// where the pixel has no sample (a miss, or nothing diffuse to shade).
layout(set = SET_PASS, binding = AO_OUT, rgba32f) uniform writeonly image2D ao_out;
// rgb: the bounce's irradiance.
layout(set = SET_PASS, binding = AO_BOUNCE_OUT, rgba32f) uniform writeonly image2D ao_bounce_out;

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

// The visible share at p (returned) and the bounce's irradiance.
vec3 ao_estimate(PrimaryHit p, ivec2 px, out vec3 bounce) {
    uint rng = pcg_hash(uint(px.x) + pcg_hash(uint(px.y) + pcg_hash(AO_SEED)));
    bool lights = (frame.flags & FRAME_AO_BOUNCE_LIGHTS) != 0u;
    bool sky_bounce = (frame.flags & FRAME_AO_BOUNCE_SKY) != 0u;
    bool bounces = lights || sky_bounce || (frame.flags & FRAME_AO_BOUNCE_EMISSION) != 0u;
    vec3 t, b;
    basis_of(p.s.normal, t, b);
    vec3 o = offset_ray(p.s.position, p.gn, p.s.extent);
    vec3 seen = vec3(0.0), all = vec3(0.0);
    bounce = vec3(0.0);
    // The surface a ray hit, whose lights from `next_light` on are still to come (then, at index
    // light_count, its environment ray), and the hit's weight.
    Surface hs;
    vec3 hv = vec3(0.0), hgn = vec3(0.0), hms = vec3(0.0), hw = vec3(0.0);
    uint done = frame.light_count + 1u, next_light = done, i = 0u;
    while (true) {
        bool shadow = next_light < done;
        vec3 ro = o, rd, light = vec3(0.0), w = vec3(0.0);
        float tmax = RAY_TMAX;
        if (shadow && next_light == frame.light_count && !sky_bounce) {
            next_light = done;
            continue;
        }
        if (shadow && next_light == frame.light_count) {
            // The environment's light at the hit: one cosine ray about its normal, the hit's SH ambient
            // where it escapes.
            next_light = done;
            rd = cosine_direction(hs.normal, rng);
            if (dot(rd, hgn) <= 0.0) continue;
            count_ray(RAY_KIND_SHADOW);
            ro = offset_ray(hs.position, hgn, hs.extent);
            light = hw * ambient_diffuse(hs, ambient_radiance(hs.normal));
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
        } else {
            if (i == AO_SAMPLES) break;
            rd = ao_direction(i++, px, t, b, p.s.normal, rng);
            w = ao_weight(rd);
            all += w;
            // Below the geometry (a normal map tilted the lobe): self-occluded, as in direct_light.
            if (dot(rd, p.gn) <= 0.0) continue;
            count_ray(RAY_KIND_SECONDARY);
        }
        RayHit h;
        vec3 tr;
        // Without the bounce a visibility ray is a shadow ray: any hit, glass passing its transmittance.
        bool hit = trace_ray(ro, rd, tmax, shadow || !bounces, h, tr);
        if (shadow) {
            if (!hit) bounce += light * tr;
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
            if ((frame.flags & FRAME_AO_BOUNCE_EMISSION) != 0u) bounce += hw * hs.emissive;
            next_light = lights ? 0u : sky_bounce ? frame.light_count : done;
        }
    }
    // Cosine-weighted rays: irradiance is pi times the mean radiance.
    bounce *= PI / float(AO_SAMPLES);
    return seen / all;
}

// Surfaces whose ambient the estimate scales: anything with a diffuse part, or an environment
// specular no traced ray corrects (mirrors and glossy lobes are traced; composite.comp).
bool ao_shades(Surface s) {
    bool diffuse = (1.0 - s.metallic) * (1.0 - s.transmission) * max3(s.base_color) > 0.0;
    return diffuse || !(is_mirror(s, 0u) || is_glossy(s, 0u));
}

void ao_pixel(ivec2 px) {
    PrimaryHit p;
    if (outside_frame(px)) return;
    if (!read_primary(px, p) || !ao_shades(p.s)) {
        imageStore(ao_out, px, vec4(1.0, 1.0, 1.0, 0.0));
        imageStore(ao_bounce_out, px, vec4(0.0));
        return;
    }
    face_viewer(p.s, -p.dir);
    vec3 bounce;
    vec3 share = ao_estimate(p, px, bounce);
    if (any(isnan(bounce)) || any(isinf(bounce))) bounce = vec3(0.0);
    imageStore(ao_out, px, vec4(share, distance(frame.camera_pos, p.s.position)));
    imageStore(ao_bounce_out, px, vec4(bounce, 0.0));
}
