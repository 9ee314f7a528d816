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

layout(location = 3) flat in uint v_instance;
#ifdef GB_CLUSTER
// The cluster's first triangle within its draw (gbuffer.vert).
layout(location = 4) flat in uint v_first_primitive;
#else
const uint v_first_primitive = 0u;
#endif

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
    o_hit = uvec2(v_instance + 1u, v_first_primitive + uint(gl_PrimitiveID));
}
