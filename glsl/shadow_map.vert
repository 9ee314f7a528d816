#version 460
// Pass `shadow_map`: depth from one light (push constant: its index and
// layer). Vertex pulling like gbuffer.vert; instances and materials that
// cast no shadow, and transmissive ones (traced shadows tint through them;
// the fallback lets them light through), are clipped away.
#include "common/scene.glsl"
#include "common/shadow_map.glsl"

layout(push_constant) uniform Push { uint light; };

void main() {
    Instance inst = instances[gl_InstanceIndex];
    Material m = materials[inst.material];
    bool casts = (inst.flags & INST_CASTS_SHADOWS) != 0u && (m.flags & MAT_CASTS_SHADOWS) != 0u && m.transmission <= 0.0;
    vec4 world = inst.world * vec4(vertices[gl_VertexIndex].position, 1.0);
    // Beyond the far plane: the whole triangle is clipped.
    gl_Position = casts ? shadow_views[light].view_proj * world : vec4(0.0, 0.0, 2.0, 1.0);
}
