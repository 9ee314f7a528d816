#version 460
// G-buffer vertex stage: pulls vertices from the shared vertex buffer (the
// same copy the ray tracers read); the instance comes from firstInstance.
#include "common/scene.glsl"

layout(location = 0) out vec3 v_normal;
layout(location = 1) out vec4 v_tangent;
layout(location = 2) out vec2 v_uv;
layout(location = 3) flat out uint v_instance;

void main() {
    Instance inst = instances[gl_InstanceIndex];
    Vertex vtx = vertices[gl_VertexIndex];
    vec4 world = inst.world * vec4(vtx.position, 1.0);
    gl_Position = frame.view_proj * world;
    v_normal = mat3(inst.normal_matrix) * vtx.normal;
    v_tangent = vec4(mat3(inst.world) * vtx.tangent.xyz, vtx.tangent.w);
    v_uv = vtx.uv;
    v_instance = gl_InstanceIndex;
}
