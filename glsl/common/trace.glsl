// Picks the traversal the variant was compiled for, behind the same
// functions: trace_closest, trace_shadow, and trace_ray (either kind, picked
// at run time: a shader that traces both kinds through ONE trace_ray call
// inlines the traversal once; lavapipe's JIT time grows with every copy):
//   TRACE_QUERY     ray queries (compute)
//   TRACE_COMPUTE   our BVH (compute)
//   TRACE_PIPELINE  traceRayEXT (ray-generation shader)
//   none of them    TRACE_NONE: no ray is traced (stubs in integrator.glsl)
#ifndef TRACE_GLSL
#define TRACE_GLSL
#if !defined(TRACE_QUERY) && !defined(TRACE_COMPUTE) && !defined(TRACE_PIPELINE)
#define TRACE_NONE
#endif
#include "hit.glsl"
#ifdef TRACE_QUERY
#include "../trace/query.glsl"
#endif
#ifdef TRACE_COMPUTE
#include "../trace/compute.glsl"
#endif
#ifdef TRACE_PIPELINE
#include "../trace/pipeline.glsl"
#endif
#if defined(TRACE_QUERY) || defined(TRACE_COMPUTE)
// Inlined traversal (driver's ray query, our BVH): both kinds are trace_ray; a kernel that traces both
// should call trace_ray once rather than these two.
bool trace_closest(vec3 o, vec3 d, float tmax, out RayHit hit) {
    vec3 unused;
    return trace_ray(o, d, tmax, false, hit, unused);
}

vec3 trace_shadow(vec3 o, vec3 d, float tmax) {
    vec3 tr;
    RayHit hit;
    return trace_ray(o, d, tmax, true, hit, tr) ? vec3(0.0) : tr;
}
#endif
#endif
