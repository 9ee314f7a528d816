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
#endif
