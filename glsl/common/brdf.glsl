// GGX / Smith height-correlated metallic-roughness BRDF (glTF 2.0 appendix B).
#ifndef BRDF_GLSL
#define BRDF_GLSL

#include "math.glsl"

struct Surface {
    vec3 position;
    float extent;     // largest |world coordinate| of its triangle (ray offsets)
    vec3 normal;      // shading normal, unit, facing the viewer's side
    vec3 base_color;
    float metallic;
    float roughness;  // perceptual
    float occlusion;
    vec3 emissive;
    float transmission;
    float ior;
    // KHR_materials_specular: the dielectric reflection's weight and the colour its F0 (the IOR's)
    // is multiplied by; 1 and white leave the IOR's reflection as it is.
    float specular;
    vec3 specular_color;
    // KHR_materials_clearcoat: a dielectric coat (F0 0.04) of this weight and perceptual roughness
    // over the rest, with its own unit normal on the viewer's side; weight 0: none.
    float clearcoat;
    float clearcoat_roughness;
    vec3 clearcoat_normal;
};

float d_ggx(float n_h, float a2) {
    float d = n_h * n_h * (a2 - 1.0) + 1.0;
    return a2 / max(PI * d * d, 1e-12);
}

float v_smith_ggx_correlated(float n_v, float n_l, float a2) {
    float gv = n_l * sqrt(n_v * n_v * (1.0 - a2) + a2);
    float gl = n_v * sqrt(n_l * n_l * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-12);
}

// Schlick's Fresnel with the grazing reflectance f90 derived from f0 (as in
// Filament): 1 for every real material (f0 >= 0.02, IOR >= 1.33), falling
// to 0 as f0 -> 0, so an IOR-1 interface (f0 = 0) reflects nothing even at
// grazing angles, as the exact dielectric Fresnel says.
float schlick_f90(vec3 f0) {
    return clamp(dot(f0, vec3(50.0 / 3.0)), 0.0, 1.0);
}

vec3 f_schlick(vec3 f0, float f90, float v_h) {
    float f = pow(clamp(1.0 - v_h, 0.0, 1.0), 5.0);
    return f0 + (f90 - f0) * f;
}

vec3 f_schlick(vec3 f0, float v_h) {
    return f_schlick(f0, schlick_f90(f0), v_h);
}

// The dielectric F0 before KHR_materials_specular's weight: the IOR's, tinted by its colour.
vec3 dielectric_f0(Surface s) {
    float f = (s.ior - 1.0) / (s.ior + 1.0);
    return min(vec3(f * f) * s.specular_color, vec3(1.0));
}

vec3 surface_f0(Surface s) {
    return mix(s.specular * dielectric_f0(s), s.base_color, s.metallic);
}

// The weight scales the dielectric's whole Fresnel curve, f90 included (KHR_materials_specular).
float surface_f90(Surface s) {
    return schlick_f90(mix(dielectric_f0(s), s.base_color, s.metallic)) * mix(s.specular, 1.0, s.metallic);
}

// The surface's Fresnel reflectance at v.h (or n.v).
vec3 surface_fresnel(Surface s, float v_h) {
    return f_schlick(surface_f0(s), surface_f90(s), v_h);
}

// Every Surface field KHR_materials_specular and KHR_materials_clearcoat add, at their "no extension"
// values.
void no_layer_extensions(inout Surface s) {
    s.specular = 1.0;
    s.specular_color = vec3(1.0);
    s.clearcoat = 0.0;
    s.clearcoat_roughness = 0.0;
    s.clearcoat_normal = s.normal;
}

// The coat's IOR 1.5 (KHR_materials_clearcoat): F0 ((1.5 - 1) / (1.5 + 1))^2.
const float COAT_F0 = 0.04;

// The share of the light towards v the coat reflects (its weight x Schlick at its n.v); the layer
// under it gets the rest (the extension's fresnel_coat).
float coat_weight(Surface s, vec3 v) {
    if (s.clearcoat <= 0.0) return 0.0;
    return s.clearcoat * f_schlick(vec3(COAT_F0), 1.0, max(dot(s.clearcoat_normal, v), 0.0)).x;
}

// The coat as a surface of its own: a black dielectric of IOR 1.5 with the coat's normal and roughness,
// whose specular lobe (brdf_lobes, split_sum.glsl) is the coat's, before its weight.
Surface coat_layer(Surface s) {
    Surface c = s;
    c.normal = s.clearcoat_normal;
    c.roughness = s.clearcoat_roughness;
    c.base_color = vec3(0.0);
    c.metallic = 0.0;
    c.transmission = 0.0;
    c.ior = 1.5;
    c.emissive = vec3(0.0);
    c.specular = 1.0;
    c.specular_color = vec3(1.0);
    c.clearcoat = 0.0;
    return c;
}

// One layer's diffuse and specular lobes towards v for light from l, each times n.l (0 below it).
void layer_lobes(Surface s, vec3 v, vec3 l, vec3 ms, out vec3 diffuse, out vec3 spec) {
    vec3 n = s.normal;
    float n_l = dot(n, l);
    diffuse = vec3(0.0);
    spec = vec3(0.0);
    if (n_l <= 0.0) return;
    float n_v = max(dot(n, v), 1e-4);
    vec3 h = normalize(l + v);
    float n_h = max(dot(n, h), 0.0);
    float v_h = max(dot(v, h), 0.0);
    float a = max(s.roughness * s.roughness, 1e-3);
    float a2 = a * a;
    vec3 f = surface_fresnel(s, v_h);
    spec = ms * f * d_ggx(n_h, a2) * v_smith_ggx_correlated(n_v, n_l, a2) * n_l;
    diffuse = (1.0 - f) * (1.0 - s.metallic) * (1.0 - s.transmission) * s.base_color / PI * n_l;
}

// The BRDF's diffuse and specular lobes towards v for light from l, each times its cosine: the base's
// (keeping 1 - coat_weight under a coat) and the coat's (weighted; single scattering: at F0 0.04
// multiple scattering adds under 2 %).
void brdf_layers(Surface s, vec3 v, vec3 l, vec3 ms, out vec3 diffuse, out vec3 spec, out vec3 coat) {
    layer_lobes(s, v, l, ms, diffuse, spec);
    coat = vec3(0.0);
    if (s.clearcoat <= 0.0) return;
    float keep = 1.0 - coat_weight(s, v);
    vec3 cd;
    layer_lobes(coat_layer(s), v, l, vec3(1.0), cd, coat);
    diffuse *= keep;
    spec *= keep;
    coat *= s.clearcoat;
}

// brdf_layers with the coat's lobe in `spec`.
void brdf_lobes(Surface s, vec3 v, vec3 l, vec3 ms, out vec3 diffuse, out vec3 spec) {
    vec3 coat;
    brdf_layers(s, v, l, ms, diffuse, spec, coat);
    spec += coat;
}

// Outgoing radiance towards v for light arriving from l with irradiance
// `e` measured perpendicular to l (so the cosine is applied here); `ms` scales the specular lobe
// (split_sum.glsl's multiple-scattering compensation; 1: single scattering).
vec3 brdf_eval_ms(Surface s, vec3 v, vec3 l, vec3 e, vec3 ms) {
    vec3 diffuse, spec;
    brdf_lobes(s, v, l, ms, diffuse, spec);
    return (diffuse + spec) * e;
}

vec3 brdf_eval(Surface s, vec3 v, vec3 l, vec3 e) {
    return brdf_eval_ms(s, v, l, e, vec3(1.0));
}

#endif
