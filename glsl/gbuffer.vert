#version 460
// G-buffer (visibility) vertex stage: pulls vertices from the shared vertex
// buffer (the same copy the ray tracers read). Only the position leaves it,
// with the triangle, plus uv with GB_UV (alpha-masked geometry): the shading
// attributes are fetched per pixel by the `gbuffer_resolve` pass, because
// every interpolated attribute costs llvmpipe set-up time per (often
// sub-pixel) triangle.
#include "common/scene.glsl"

#ifdef GB_UV
layout(location = 2) out vec2 v_uv;
#endif
// Non-indexed draws (common/gbuffer_draw.glsl), of a whole instance or of
// one of its clusters (occlusion culling, render/occlusion.rs: the cluster's
// draw starts at its first index): vertex k of the draw is corner k % 3 of
// the draw's triangle (k - first_index) / 3.
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
