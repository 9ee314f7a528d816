#version 460
// G-buffer raster, visibility-buffer variant: stores only (instance + 1, primitive) and depth;
// `gbuffer_resolve` fills the material targets. The old four-MRT pass spent most of its llvmpipe time
// on attribute set-up of tiny triangles (bench/results/lavapipe-2core-vm-raster.md). GB_ALPHA_TEST
// geometry still interpolates uv for its alpha test.
#include "common/scene.glsl"
#ifdef GB_ALPHA_TEST
#define MAT_SAMPLE(index, xf, uv, fallback) sample_tex(index, xf, uv, fallback)
#include "common/material.glsl"
layout(location = 2) in vec2 v_uv;
#endif

// The triangle comes as a flat varying, not gl_PrimitiveID (see common/gbuffer_draw.glsl).
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
