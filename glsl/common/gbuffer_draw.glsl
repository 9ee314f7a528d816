// Per-draw constants of the G-buffer raster (render/passes/gbuffer.rs, GBufferDraw). The world
// matrix avoids a per-vertex instance fetch (same f32 matrix, same positions to the bit); the
// instance is written to the hit target without a flat varying; draws are not indexed, so the vertex
// stage fetches its index and the triangle number comes from gl_VertexIndex rather than
// gl_PrimitiveID, whose fragment-stage use puts llvmpipe on a slower primitive-assembly path.
// Together ~1/3 of the pass on Sponza (bench/results/lavapipe-2core-vm-raster.md).
#ifndef GBUFFER_DRAW_GLSL
#define GBUFFER_DRAW_GLSL
layout(push_constant) uniform GBufferDraw {
    mat4 world;
    uint instance;
    uint first_index;
    int vertex_offset;
} gb_draw;
#endif
