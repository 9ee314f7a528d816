#version 460
// G-buffer (visibility) vertex stage: pulls vertices from the shared vertex
// buffer (the same copy the ray tracers read); the instance comes from
// firstInstance. Only the position and the instance leave it, plus uv with
// GB_UV (alpha-masked geometry): the shading attributes are fetched per
// pixel by the `gbuffer_resolve` pass, because every interpolated attribute
// costs llvmpipe set-up time per (often sub-pixel) triangle.
#include "common/scene.glsl"

#ifdef GB_UV
layout(location = 2) out vec2 v_uv;
#endif
layout(location = 3) flat out uint v_instance;
#ifdef GB_CLUSTER
// Occlusion culling draws clusters (render/occlusion.rs): firstInstance is
// the cluster, which names the instance and its first triangle.
#include "common/cluster.glsl"
layout(location = 4) flat out uint v_first_primitive;
#endif

void main() {
#ifdef GB_CLUSTER
    Cluster cluster = clusters[gl_InstanceIndex];
    uint instance = cluster.instance;
    v_first_primitive = cluster.first_primitive;
#else
    uint instance = gl_InstanceIndex;
#endif
    Instance inst = instances[instance];
    Vertex vtx = vertices[gl_VertexIndex];
    gl_Position = frame.view_proj * (inst.world * vec4(vtx.position, 1.0));
#ifdef GB_UV
    v_uv = vtx.uv;
#endif
    v_instance = instance;
}
