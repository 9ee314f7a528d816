#version 460
// G-buffer fragment stage: material attributes into the MRT targets, plus
// (instance, primitive) so later passes reconstruct the exact primary hit.
#include "common/scene.glsl"
#define MAT_SAMPLE(index, uv, fallback) sample_tex(index, uv, fallback)
#include "common/material.glsl"
#include "common/srgb.glsl"
#include "common/gbuffer_pack.glsl"

layout(constant_id = SPEC_ALPHA_TEST) const bool ALPHA_TEST = false;

layout(location = 0) in vec3 v_normal;
layout(location = 1) in vec4 v_tangent;
layout(location = 2) in vec2 v_uv;
layout(location = 3) flat in uint v_instance;

layout(location = 0) out vec4 o_albedo;    // rgb base colour (sRGB-encoded), a occlusion
layout(location = 1) out uint o_normal;    // world shading normal, octahedral (gbuffer_pack.glsl)
layout(location = 2) out vec4 o_material;  // r metallic, g roughness, b transmission
layout(location = 3) out uvec2 o_hit;      // instance + 1, primitive
// No emission target: readers look it up from the material at the hit.

void main() {
    Instance inst = instances[v_instance];
    Material m = materials[inst.material];
    Surface s;
    float alpha;
    material_eval(m, v_uv, s, alpha);
    if (ALPHA_TEST && alpha < m.alpha_cutoff) {
        discard;
    }
    // Guard against degenerate interpolated vectors (zero-area or bad input).
    vec3 n = dot(v_normal, v_normal) > 1e-20 ? normalize(v_normal) : vec3(0.0, 1.0, 0.0);
    if (!gl_FrontFacing) n = -n;
    n = apply_normal_map(m, v_uv, n, v_tangent);

    o_albedo = vec4(srgb_encode(s.base_color), s.occlusion);
    o_normal = oct_encode(n);
    o_material = vec4(s.metallic, s.roughness, s.transmission, 0.0);
    o_hit = uvec2(v_instance + 1u, uint(gl_PrimitiveID));
}
