#version 460
// G-buffer raster, visibility-buffer variant: stores only each pixel's
// (instance + 1, primitive) and depth; the `gbuffer_resolve` pass fills the
// material targets from that triangle. On llvmpipe the old pass (four MRTs,
// nine interpolated floats) spent most of its time setting up and
// interpolating attributes of tiny triangles (bench/results/
// lavapipe-2core-vm-raster.md). Alpha-masked geometry (GB_ALPHA_TEST) still
// interpolates uv and tests the base colour's alpha as before.
#include "common/scene.glsl"
#ifdef GB_ALPHA_TEST
#define MAT_SAMPLE(index, uv, fallback) sample_tex(index, uv, fallback)
#include "common/material.glsl"
layout(location = 2) in vec2 v_uv;
#endif

// Draws of one instance (a whole one or clusters of it): its index is a
// push constant, the triangle a flat varying (gbuffer.vert; not
// gl_PrimitiveID: common/gbuffer_draw.glsl).
#include "common/gbuffer_draw.glsl"
#define v_instance gb_draw.instance
layout(location = 4) flat in uint v_primitive;

layout(location = 0) out uvec2 o_hit;  // instance + 1, primitive

void main() {
#ifdef GB_ALPHA_TEST
    Material m = materials[instances[v_instance].material];
    Surface s;
    float alpha;
    material_eval(m, v_uv, s, alpha);
    if (alpha < m.alpha_cutoff) {
        discard;
    }
#endif
    o_hit = uvec2(v_instance + 1u, v_primitive);
}
