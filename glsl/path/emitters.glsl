// Emissive triangles as lights (table: gpu/emitters.rs, layout SCENE_EMITTERS): a triangle by power,
// a uniform point on it, solid-angle pdf for the MIS weights. Two-sided, as hit_surface shades it.
#ifndef EMITTERS_GLSL
#define EMITTERS_GLSL
#include "../common/hit.glsl"
#include "../common/sampling.glsl"

layout(set = SET_SCENE, binding = SCENE_EMITTERS, scalar) readonly buffer Emitters { uint emitters[]; };

uint emitter_count() {
    return emitters[0];
}

uint emitter_pairs() {
    return EMITTER_HEADER_WORDS + emitters[1];
}

float emitter_cdf(uint k) {
    return uintBitsToFloat(emitters[emitter_pairs() + 2u * emitters[0] + k]);
}

// The probability that the light sample picks triangle `primitive` of
// `instance` (0: it is not an emitter).
float emitter_choice(uint instance, uint primitive) {
    if (emitter_count() == 0u || instance >= emitters[1]) return 0.0;
    uint first = emitters[EMITTER_HEADER_WORDS + instance];
    if (first == NO_EMITTER) return 0.0;
    return emitter_cdf(first + primitive + 1u) - emitter_cdf(first + primitive);
}

// Solid-angle pdf of a light sample landing on a triangle of world area
// `area`, seen at distance `dist` under cosine `cos_l` to its normal.
float emitter_pdf(float choice, float area, float dist, float cos_l) {
    return choice * dist * dist / max(area * cos_l, 1e-30);
}

float triangle_area(TriangleWorld t, out vec3 n) {
    vec3 c = cross(t.p1 - t.p0, t.p2 - t.p0);
    float len = length(c);
    n = len > 0.0 ? c / len : vec3(0.0, 1.0, 0.0);
    return 0.5 * len;
}

// Picks an emitter triangle by power and a uniform point on it: the hit a
// ray towards it would report (t unset), and the choice's probability.
bool sample_emitter(inout uint rng, out RayHit h, out float choice) {
    uint n = emitter_count();
    if (n == 0u) return false;
    float u = next_random(rng);
    uint lo = 0u, hi = n;
    while (lo + 1u < hi) {
        uint mid = (lo + hi) >> 1u;
        if (emitter_cdf(mid) <= u) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    choice = emitter_cdf(lo + 1u) - emitter_cdf(lo);
    uint base = emitter_pairs() + 2u * lo;
    float r = sqrt(next_random(rng)), v = next_random(rng);
    h = RayHit(emitters[base], emitters[base + 1u], vec2(r * (1.0 - v), r * v), 0.0);
    return choice > 0.0;
}

// A light sample on the emissive triangles seen from p: direction d, distance t, the radiance le the
// point sends towards p, and the solid-angle pdf. False where it cannot light p (a degenerate
// triangle, a cut-out texel, no emission).
struct EmitterSample {
    vec3 d;
    float t;
    vec3 le;
    float pdf;
};

bool sample_emitter_light(vec3 p, inout uint rng, out EmitterSample es) {
    es = EmitterSample(vec3(0.0, 0.0, 1.0), 0.0, vec3(0.0), 0.0);
    RayHit e;
    float choice;
    if (!sample_emitter(rng, e, choice)) return false;
    TriangleWorld tw = triangle_world(e.instance, e.primitive);
    vec3 en;
    float area = triangle_area(tw, en);
    vec3 b = bary3(e.bary);
    vec3 to = tw.p0 * b.x + tw.p1 * b.y + tw.p2 * b.z - p;
    e.t = length(to);
    es.t = e.t;
    es.d = to / max(e.t, 1e-30);
    float cos_l = abs(dot(en, es.d));
    if (!(e.t > 0.0 && cos_l > 0.0 && hit_alpha_passes(e.instance, e.primitive, e.bary, e.t))) return false;
    es.pdf = emitter_pdf(choice, area, e.t, cos_l);
    vec3 egn;
    bool eback;
    es.le = hit_surface(e, p, es.d, 0.0, egn, eback).emissive;
    return es.pdf > 0.0 && any(greaterThan(es.le, vec3(0.0)));
}

// The solid-angle pdf with which a light sample would have chosen the direction `dir` of a ray that
// hit `h` (0: no emitter the table holds).
float emitter_hit_pdf(RayHit h, vec3 dir) {
    float choice = emitter_choice(h.instance, h.primitive);
    if (choice <= 0.0) return 0.0;
    vec3 en;
    float area = triangle_area(triangle_world(h.instance, h.primitive), en);
    return emitter_pdf(choice, area, h.t, abs(dot(en, dir)));
}

#endif
