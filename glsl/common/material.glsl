// Material evaluation shared by the G-buffer pass (implicit derivatives)
// and ray hits (explicit LOD). The includer defines
//   MAT_SAMPLE(index, transform, uv, fallback)
// before including this file.
#ifndef MATERIAL_GLSL
#define MATERIAL_GLSL
#include "scene.glsl"
#include "brdf.glsl"

// Fills the material part of `s` (not position/normal) from material `m` at `uv`.
void material_eval(Material m, vec2 uv, inout Surface s, out float alpha) {
    vec4 base = m.base_color * MAT_SAMPLE(m.tex_base_color, m.uv_base_color, uv, vec4(1.0));
    vec4 mr = MAT_SAMPLE(m.tex_metallic_roughness, m.uv_metallic_roughness, uv, vec4(1.0));
    s.base_color = base.rgb;
    alpha = base.a;
    s.roughness = clamp(m.roughness * mr.g, 0.0, 1.0);
    s.metallic = clamp(m.metallic * mr.b, 0.0, 1.0);
    s.occlusion = 1.0 + m.occlusion_strength * (MAT_SAMPLE(m.tex_occlusion, m.uv_occlusion, uv, vec4(1.0)).r - 1.0);
    s.emissive = m.emissive * MAT_SAMPLE(m.tex_emissive, m.uv_emissive, uv, vec4(1.0)).rgb;
    s.transmission = clamp(m.transmission * MAT_SAMPLE(m.tex_transmission, m.uv_transmission, uv, vec4(1.0)).r, 0.0, 1.0);
    s.ior = m.ior;
    s.specular = clamp(m.specular * MAT_SAMPLE(m.tex_specular, m.uv_specular, uv, vec4(1.0)).a, 0.0, 1.0);
    s.specular_color = m.specular_color * MAT_SAMPLE(m.tex_specular_color, m.uv_specular_color, uv, vec4(1.0)).rgb;
    // The coat's normal is the includer's (coat_normal).
    s.clearcoat = 0.0;
    s.clearcoat_roughness = 0.0;
    if (m.clearcoat > 0.0) {
        s.clearcoat = clamp(m.clearcoat * MAT_SAMPLE(m.tex_clearcoat, m.uv_clearcoat, uv, vec4(1.0)).r, 0.0, 1.0);
        s.clearcoat_roughness = clamp(
            m.clearcoat_roughness * MAT_SAMPLE(m.tex_clearcoat_roughness, m.uv_clearcoat_roughness, uv, vec4(1.0)).g,
            0.0, 1.0);
    }
}

// Perturbs the unit normal `n` by normal map `tex` (transform `xf`, strength `scale`; -1: none).
// Degenerate tangents leave `n` unchanged rather than producing NaN.
vec3 normal_from_map(int tex, UvTransform xf, float scale, vec2 uv, vec3 n, vec4 tangent) {
    if (tex < 0) return n;
    vec3 t = tangent.xyz - n * dot(n, tangent.xyz);
    if (dot(t, t) <= 1e-20) return n;
    t = normalize(t);
    vec3 b = cross(n, t) * (tangent.w < 0.0 ? -1.0 : 1.0);
    // KHR_texture_transform turns the map on the surface: its axes are those of the transformed uv,
    // (dp/du', dp/dv') = (t, b) L^-1 for the transform's linear part L, re-orthonormalized as generated
    // tangents are (so a transform renders as the same UVs baked into the vertices).
    float det = xf.row0.x * xf.row1.y - xf.row0.y * xf.row1.x;
    if (abs(det) > 1e-12) {
        vec3 du = (t * xf.row1.y - b * xf.row1.x) / det;
        vec3 dv = (b * xf.row0.x - t * xf.row0.y) / det;
        du -= n * dot(n, du);
        if (dot(du, du) <= 1e-20) return n;
        t = normalize(du);
        b = cross(n, t) * (dot(cross(n, t), dv) < 0.0 ? -1.0 : 1.0);
    }
    vec3 tn = MAT_SAMPLE(tex, xf, uv, vec4(0.5, 0.5, 1.0, 1.0)).xyz * 2.0 - 1.0;
    tn.xy *= scale;
    vec3 mapped = t * tn.x + b * tn.y + n * tn.z;
    return dot(mapped, mapped) > 1e-20 ? normalize(mapped) : n;
}

// The material's normal map on the interpolated vertex normal `n`.
vec3 apply_normal_map(Material m, vec2 uv, vec3 n, vec4 tangent) {
    return normal_from_map(m.tex_normal, m.uv_normal, m.normal_scale, uv, n, tangent);
}

// KHR_materials_clearcoat's normal: its own map on `n`, or `n` itself (not the base's normal map).
vec3 coat_normal(Material m, vec2 uv, vec3 n, vec4 tangent) {
    return normal_from_map(m.tex_clearcoat_normal, m.uv_clearcoat_normal, m.clearcoat_normal_scale, uv, n, tangent);
}

#endif
