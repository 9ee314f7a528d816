#version 460
// G-buffer fragment stage: material attributes into the MRT targets, plus
// (instance, primitive) so later passes reconstruct the exact primary hit.
#include "common/scene.glsl"

layout(constant_id = 0) const bool ALPHA_TEST = false;

layout(location = 0) in vec3 v_normal;
layout(location = 1) in vec4 v_tangent;
layout(location = 2) in vec2 v_uv;
layout(location = 3) flat in uint v_instance;

layout(location = 0) out vec4 o_albedo;    // rgb base colour, a occlusion
layout(location = 1) out vec4 o_normal;    // xyz world shading normal, w roughness
layout(location = 2) out vec4 o_material;  // r metallic, g transmission, b (ior-1)/2
layout(location = 3) out vec4 o_emissive;  // rgb emitted radiance
layout(location = 4) out uvec2 o_hit;      // instance + 1, primitive

void main() {
    Instance inst = instances[v_instance];
    Material m = materials[inst.material];
    vec4 base = m.base_color * sample_tex(m.tex_base_color, v_uv, vec4(1.0));
    if (ALPHA_TEST && base.a < m.alpha_cutoff) {
        discard;
    }
    vec4 mr = sample_tex(m.tex_metallic_roughness, v_uv, vec4(1.0));
    float roughness = clamp(m.roughness * mr.g, 0.0, 1.0);
    float metallic = clamp(m.metallic * mr.b, 0.0, 1.0);
    float occlusion = 1.0 + m.occlusion_strength * (sample_tex(m.tex_occlusion, v_uv, vec4(1.0)).r - 1.0);
    vec3 emissive = m.emissive * sample_tex(m.tex_emissive, v_uv, vec4(1.0)).rgb;
    float transmission = m.transmission * sample_tex(m.tex_transmission, v_uv, vec4(1.0)).r;

    // Guard against degenerate interpolated vectors (zero-area or bad input).
    vec3 n = v_normal;
    n = dot(n, n) > 1e-20 ? normalize(n) : vec3(0.0, 1.0, 0.0);
    if (!gl_FrontFacing) n = -n;
    if (m.tex_normal >= 0) {
        vec3 t = v_tangent.xyz - n * dot(n, v_tangent.xyz);
        if (dot(t, t) > 1e-20) {
            t = normalize(t);
            vec3 b = cross(n, t) * (v_tangent.w < 0.0 ? -1.0 : 1.0);
            vec3 tn = sample_tex(m.tex_normal, v_uv, vec4(0.5, 0.5, 1.0, 1.0)).xyz * 2.0 - 1.0;
            tn.xy *= m.normal_scale;
            vec3 mapped = t * tn.x + b * tn.y + n * tn.z;
            if (dot(mapped, mapped) > 1e-20) n = normalize(mapped);
        }
    }

    o_albedo = vec4(base.rgb, occlusion);
    o_normal = vec4(n, roughness);
    o_material = vec4(metallic, transmission, clamp((m.ior - 1.0) * 0.5, 0.0, 1.0), 0.0);
    o_emissive = vec4(emissive, 0.0);
    o_hit = uvec2(v_instance + 1u, uint(gl_PrimitiveID));
}
