// Per-draw constants of the G-buffer raster, whole draws and cluster draws
// alike (render/passes/gbuffer.rs, GBufferDraw): the instance's world matrix, so
// the vertex stage fetches no instance per vertex (the same f32 matrix the
// instance buffer holds, applied the same way: the same positions as the
// fetch, to the bit); the instance, which the fragment stage writes into the hit target (no
// flat varying for it); and the draw's index range, since the draw is not
// indexed: the vertex stage fetches its index itself, so that the triangle
// number is gl_VertexIndex's (a flat varying) rather than gl_PrimitiveID,
// whose use in the fragment stage makes llvmpipe assemble primitives on a
// slower path. Together they cut ~1/3 of the pass on Sponza
// (bench/results/lavapipe-2core-vm-raster.md).
#ifndef GBUFFER_DRAW_GLSL
#define GBUFFER_DRAW_GLSL
layout(push_constant) uniform GBufferDraw {
    mat4 world;
    uint instance;
    uint first_index;
    int vertex_offset;
} gb_draw;
#endif
