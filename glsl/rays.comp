#version 460
// Ray microbenchmark as a compute shader: one invocation per ray
// (passes/rays.glsl), traced by the variant's traversal (rays_query,
// rays_compute, rays_compute_stats: glsl/variants.txt).
#include "passes/rays.glsl"

layout(local_size_x = 64) in;

#ifdef TRACE_NONE
// The plain rays.comp build.rs also compiles has no traversal: it traces
// nothing and no pipeline loads it.
void main() {}
#else
void main() {
    trace_bench_ray(gl_GlobalInvocationID.x);
}
#endif
