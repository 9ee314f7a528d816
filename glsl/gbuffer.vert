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

void main() {
    Instance inst = instances[gl_InstanceIndex];
    Vertex vtx = vertices[gl_VertexIndex];
    gl_Position = frame.view_proj * (inst.world * vec4(vtx.position, 1.0));
#ifdef GB_UV
    v_uv = vtx.uv;
#endif
    v_instance = gl_InstanceIndex;
}
