// Pass `path` (`--mode path`): the ground truth, a unidirectional path tracer on the same scene and
// traversal. Box-filtered jittered camera rays; NEE at every non-delta vertex to each punctual light,
// one environment sample and one emissive triangle (by power), MIS with the BSDF sample (power
// heuristic); Russian roulette from PATH_RR_START; at most Frame.accum_bounces bounces. Shadow rays
// see glass as opaque (FRAME_OPAQUE_OCCLUDERS): its light comes along refracted paths. Sums kept in f32
// with their count; PCG seeded by pixel and Frame.accum_frame so every backend traces the same paths.
#include "../common/integrator.glsl"
#include "../common/sampling.glsl"
#include "env_sampling.glsl"
#include "emitters.glsl"
#include "bsdf.glsl"

layout(set = SET_PASS, binding = PATH_ACCUM, rgba32f) uniform image2D path_accum;
layout(set = SET_PASS, binding = PATH_OUT, rgba32f) uniform writeonly image2D hdr_out;

// A normal map can tilt the shading frame past the geometric normal; a direction on the wrong side
// of the geometry would leak light through the surface.
bool consistent_side(vec3 l_world, float l_local_z, vec3 gn) {
    return (dot(l_world, gn) > 0.0) == (l_local_z > 0.0);
}

// NEE candidate k at a vertex: punctual light k, then (k == light_count) one emissive triangle, then
// the environment (MIS-weighted), in that order (the random numbers they draw). False where it brings
// nothing; else `c` is its contribution if unblocked along `d` up to `tmax` (`shadowed`: a shadow ray
// decides; a light that casts no shadow does not need one).
bool nee_candidate(uint k, Surface s, vec3 gn, Bsdf m, vec3 v, inout uint rng, out vec3 c, out vec3 d,
                   out float tmax, out bool shadowed) {
    float unused;
    c = vec3(0.0);
    tmax = RAY_TMAX;
    shadowed = true;
    if (k < frame.light_count) {
        Light light = lights[k];
        LightSample ls = sample_light(light, s.position);
        d = ls.l;
        vec3 l = bsdf_local(m, d);
        if (!consistent_side(d, l.z, gn)) return false;
        c = bsdf_eval(m, v, l, unused) * ls.irradiance;
        shadowed = (light.flags & LIGHT_CASTS_SHADOWS) != 0u;
        if (light.type != LIGHT_DIRECTIONAL) tmax = ls.distance * (1.0 - 1e-4);
    } else if (k == frame.light_count) {
        EmitterSample es;
        d = vec3(0.0, 0.0, 1.0);
        if (!sample_emitter_light(s.position, rng, es)) return false;
        d = es.d;
        vec3 l = bsdf_local(m, d);
        if (!consistent_side(d, l.z, gn)) return false;
        float pdf_bsdf;
        c = bsdf_eval(m, v, l, pdf_bsdf) * es.le * (power_heuristic(es.pdf, pdf_bsdf) / es.pdf);
        // Stops short of the emitter itself.
        tmax = es.t * (1.0 - 1e-3);
    } else {
        d = vec3(0.0, 0.0, 1.0);
        if (!env_emits()) return false;
        float pdf_env, pdf_bsdf;
        d = env_sample(rng, pdf_env);
        vec3 l = bsdf_local(m, d);
        if (!(pdf_env > 0.0 && consistent_side(d, l.z, gn))) return false;
        c = bsdf_eval(m, v, l, pdf_bsdf) * environment(d);
        c *= power_heuristic(pdf_env, pdf_bsdf) / pdf_env;
    }
    return max3(c) > 0.0;
}

// The BSDF sample at a vertex continues the path (o, dir); false where the path ends there.
bool continue_path(Surface s, vec3 gn, Bsdf m, vec3 v, inout uint rng, inout vec3 throughput, out vec3 o,
                   out vec3 dir, out float prev_pdf, out bool prev_delta, uint bounce) {
    o = s.position;
    dir = vec3(0.0, 0.0, 1.0);
    prev_pdf = 0.0;
    prev_delta = true;
    BsdfSample bs;
    if (!bsdf_sample(m, v, rng, bs)) return false;
    vec3 l = normalize(bsdf_world(m, bs.l));
    if (!consistent_side(l, bs.l.z, gn)) return false;
    throughput *= bs.weight;
    if (!(max3(throughput) > 0.0) || any(isinf(throughput))) return false;  // also NaN
    o = offset_ray(s.position, bs.l.z > 0.0 ? gn : -gn, s.extent);
    dir = l;
    prev_pdf = bs.pdf;
    prev_delta = bs.delta;
    if (bounce + 1u >= PATH_RR_START) {
        // Capped at 0.95 so paths in a closed white scene still end.
        float q = min(max3(throughput), 0.95);
        if (next_random(rng) >= q) return false;
        throughput /= q;
    }
    return true;
}

#define NO_VERTEX 0xFFFFFFFFu

// One ray per iteration, path and shadow rays alike, through ONE trace_ray call: every call inlines the
// whole traversal, and lavapipe's JIT time grows steeply with the code. After each hit the vertex's
// NEE candidates come one per iteration (k), then its BSDF sample continues the path.
vec3 path_radiance(ivec2 px, inout uint rng) {
    vec2 jitter = vec2(next_random(rng), next_random(rng));
    vec3 dir = camera_ray_dir(vec2(px) + jitter);
    vec3 o = frame.camera_pos;
    vec3 throughput = vec3(1.0), radiance = vec3(0.0);
    // A delta lobe (or the camera) sees the environment whole; a BSDF sample shares it via MIS.
    float prev_pdf = 0.0;
    bool prev_delta = true;
    uint bounce = 0u;
    // The vertex whose light samples are under way: candidate k next, of `candidates`.
    Surface s;
    vec3 gn = vec3(0.0), v = vec3(0.0);
    Bsdf m;
    uint k = NO_VERTEX;
    uint candidates = frame.light_count + 2u;
    while (true) {
        bool shadow = k < candidates;
        vec3 ro = o, rd = dir, sample_c = vec3(0.0);
        float tmax = RAY_TMAX;
        if (shadow) {
            if (!nee_candidate(k++, s, gn, m, v, rng, sample_c, rd, tmax, shadow)) continue;
            if (!shadow) {
                radiance += throughput * sample_c;
                continue;
            }
            ro = offset_ray(s.position, dot(rd, gn) > 0.0 ? gn : -gn, s.extent);
            count_ray(RAY_KIND_SHADOW);
        } else {
            if (k == candidates) {
                k = NO_VERTEX;
                if (!continue_path(s, gn, m, v, rng, throughput, o, dir, prev_pdf, prev_delta, bounce)) break;
                bounce++;
                ro = o;
                rd = dir;
            }
            count_ray(bounce == 0u ? RAY_KIND_CAMERA : RAY_KIND_SECONDARY);
        }
        RayHit h;
        vec3 tr;
        bool hit = trace_ray(ro, rd, tmax, shadow, h, tr);
        if (shadow) {
            if (!hit) radiance += throughput * sample_c * tr.x;
            continue;
        }
        if (!hit) {
            float w = prev_delta || !env_emits() ? 1.0 : power_heuristic(prev_pdf, env_pdf(dir));
            radiance += throughput * environment(dir) * w;
            break;
        }
        bool back_face;
        s = hit_surface(h, o, dir, 0.0, gn, back_face);
        // Leaving a mesh from inside: the path crossed its medium.
        if (back_face) throughput *= volume_transmittance(h);
        if (max3(s.emissive) > 0.0) {
            // MIS only for emitters the light samples could have picked.
            float pdf_light = prev_delta ? 0.0 : emitter_hit_pdf(h, dir);
            float w = pdf_light > 0.0 ? power_heuristic(prev_pdf, pdf_light) : 1.0;
            radiance += throughput * s.emissive * w;
        }
        if (bounce >= frame.accum_bounces) break;
        vec3 v_world = -dir;
        face_viewer(s, v_world);
        m = bsdf_at(s, v_world, back_face);
        v = bsdf_local(m, v_world);
        k = 0u;
    }
    return radiance;
}

void path_pixel(ivec2 px) {
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    uint rng = pcg_hash(uint(px.x) + pcg_hash(uint(px.y) + pcg_hash(frame.accum_frame ^ 0x2545f491u)));
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < PATH_SAMPLES_PER_FRAME; ++i) {
        vec3 c = path_radiance(px, rng);
        // A non-finite sample would poison the accumulation; --clamp is the explicit, reported bias.
        if (any(isnan(c)) || any(isinf(c))) c = vec3(0.0);
        if (frame.path_clamp > 0.0 && max3(c) > frame.path_clamp) c *= frame.path_clamp / max3(c);
        sum += c;
    }
    vec4 acc = vec4(sum, float(PATH_SAMPLES_PER_FRAME));
    if (frame.accum_frame != 0u) acc += imageLoad(path_accum, px);
    imageStore(path_accum, px, acc);
    imageStore(hdr_out, px, vec4(acc.rgb / acc.a, 1.0));
}
