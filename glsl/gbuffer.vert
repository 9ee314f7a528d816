#version 460
// G-buffer (visibility) vertex stage: pulls vertices from the shared vertex
// buffer (the same copy the ray tracers read). Only the position leaves it,
// with the triangle (or, drawing clusters, the instance and the cluster's
// first triangle), plus uv with GB_UV (alpha-masked geometry): the shading
// attributes are fetched per pixel by the `gbuffer_resolve` pass, because
// every interpolated attribute costs llvmpipe set-up time per (often
// sub-pixel) triangle.
#include "common/scene.glsl"

#ifdef GB_UV
layout(location = 2) out vec2 v_uv;
#endif
#ifdef GB_CLUSTER
// Occlusion culling draws clusters (render/occlusion.rs): firstInstance is
// the cluster, which names the instance and its first triangle.
#include "common/cluster.glsl"
layout(location = 3) flat out uint v_instance;
layout(location = 4) flat out uint v_first_primitive;
#else
// One non-indexed draw per instance (common/gbuffer_draw.glsl): vertex k of
// the draw is corner k % 3 of triangle k / 3.
#include "common/gbuffer_draw.glsl"
layout(location = 4) flat out uint v_primitive;
#endif

void main() {
#ifdef GB_CLUSTER
    Cluster cluster = clusters[gl_InstanceIndex];
    Vertex vtx = vertices[gl_VertexIndex];
    v_instance = cluster.instance;
    v_first_primitive = cluster.first_primitive;
    gl_Position = frame.view_proj * (instances[cluster.instance].world * vec4(vtx.position, 1.0));
#else
    Vertex vtx = vertices[int(indices[gl_VertexIndex]) + gb_draw.vertex_offset];
    v_primitive = (uint(gl_VertexIndex) - gb_draw.first_index) / 3u;
    gl_Position = frame.view_proj * (gb_draw.world * vec4(vtx.position, 1.0));
#endif
#ifdef GB_UV
    v_uv = vtx.uv;
#endif
}
