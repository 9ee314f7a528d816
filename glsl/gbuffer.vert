#version 460
// G-buffer (visibility) vertex stage, pulling from the shared vertex buffer. Only position, triangle
// and (GB_UV) uv leave it: `gbuffer_resolve` fetches shading attributes per pixel, since each
// interpolated attribute costs llvmpipe set-up time per (often sub-pixel) triangle.
#include "common/scene.glsl"

#ifdef GB_UV
layout(location = 2) out vec2 v_uv;
#endif
// Non-indexed draws of an instance or one of its clusters (render/occlusion.rs): vertex k is corner
// k % 3 of triangle (k - first_index) / 3.
#include "common/gbuffer_draw.glsl"
layout(location = 4) flat out uint v_primitive;

void main() {
    Vertex vtx = vertices[int(indices[gl_VertexIndex]) + gb_draw.vertex_offset];
    v_primitive = (uint(gl_VertexIndex) - gb_draw.first_index) / 3u;
    gl_Position = frame.view_proj * (gb_draw.world * vec4(vtx.position, 1.0));
#ifdef GB_UV
    v_uv = vtx.uv;
#endif
}
