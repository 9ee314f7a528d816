// Ray microbenchmark (`bench --rays`, render/rays/mod.rs): one ray of a fixed set per invocation.
// Closest-hit rays report the hit and the next ray's origin and normal (the host builds the shadow
// and diffuse sets from the primary hits); shadow rays report blocking and transmittance.
#ifndef PASS_RAYS_GLSL
#define PASS_RAYS_GLSL
#include "../common/scene.glsl"
#include "../common/hit.glsl"
#include "../common/primary_hit.glsl"
#include "../common/trace.glsl"

struct BenchRay {
    vec3 origin;
    float tmax;
    vec3 dir;
    uint pad;
};

struct BenchResult {
    float t;         // closest hit distance (closest-hit rays), 0 otherwise
    uint instance;
    uint primitive;
    uint hit;        // 1: hit (closest) or blocked (shadow)
    vec3 next;       // offset hit point (closest) or transmittance (shadow)
    float pad0;
    vec3 normal;     // geometric normal facing the ray (closest)
    float pad1;
};

layout(set = SET_PASS, binding = RAYS_IN, scalar) readonly buffer Rays { BenchRay rays[]; };
layout(set = SET_PASS, binding = RAYS_OUT, scalar) writeonly buffer Results { BenchResult results[]; };
layout(set = SET_PASS, binding = RAYS_STATS, scalar) writeonly buffer Stats { uvec4 stats[]; };

layout(push_constant) uniform Push {
    uint count;
    uint shadow;  // 1: any-hit shadow rays, 0: closest hit
};

#ifndef TRACE_NONE
void trace_bench_ray(uint i) {
    if (i >= count) return;
    BenchRay r = rays[i];
    BenchResult res;
    res.t = 0.0;
    res.instance = 0u;
    res.primitive = 0u;
    res.hit = 0u;
    res.next = vec3(0.0);
    res.pad0 = 0.0;
    res.normal = vec3(0.0);
    res.pad1 = 0.0;
    // One trace_ray call for both kinds: each call inlines the whole traversal.
    RayHit h;
    vec3 tr;
    bool hit = trace_ray(r.origin, r.dir, r.tmax, shadow != 0u, h, tr);
    if (shadow != 0u) {
        tr = hit ? vec3(0.0) : tr;
        res.hit = all(equal(tr, vec3(0.0))) ? 1u : 0u;
        res.next = tr;
    } else {
        if (hit) {
            TriangleWorld tri = triangle_world(h.instance, h.primitive);
            vec3 p = interpolate(tri, h.bary);
            vec3 gn = cross(tri.p1 - tri.p0, tri.p2 - tri.p0);
            gn = dot(gn, gn) > 0.0 ? normalize(gn) : -r.dir;
            if (dot(gn, r.dir) > 0.0) gn = -gn;
            res.t = h.t;
            res.instance = h.instance;
            res.primitive = h.primitive;
            res.hit = 1u;
            res.next = offset_ray(p, gn, triangle_extent(tri.p0, tri.p1, tri.p2));
            res.normal = gn;
        }
    }
    results[i] = res;
#ifdef TRACE_STATS
    stats[i] = uvec4(g_stat_nodes, g_stat_tris, g_stat_lane_nodes, 0u);
#endif
}
#endif  // TRACE_NONE
#endif
