// Dielectric interface: exact Fresnel reflectance and the refracted
// direction, sharing one Snell term so they agree on total internal
// reflection. Closed-form tests: tests/render/shading_closed_form.rs.
#ifndef FRESNEL_GLSL
#define FRESNEL_GLSL

// cos²θt by Snell's law, written 1 - η² + η²cos²θi rather than
// 1 - η²(1 - cos²θi): at η = 1 it is exactly cos²θi, so a grazing ray
// (cos θi ~ 1e-4) through an IOR-1 interface neither rounds into total
// internal reflection nor bends. <= 0 with eta > 1: total internal reflection.
float cos2_transmitted(float cos_i, float eta) {
    return (1.0 - eta * eta) + eta * eta * cos_i * cos_i;
}

// Exact unpolarized Fresnel reflectance of a dielectric interface; eta =
// n_incident / n_transmitted; 1 under total internal reflection (only
// possible for eta > 1).
float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float cos2_t = cos2_transmitted(cos_i, eta);
    if (eta > 1.0 && cos2_t <= 0.0) return 1.0;
    float cos_t = sqrt(max(cos2_t, 0.0));
    float rs = (eta * cos_i - cos_t) / max(eta * cos_i + cos_t, 1e-30);
    float rp = (cos_i - eta * cos_t) / max(cos_i + eta * cos_t, 1e-30);
    return clamp(0.5 * (rs * rs + rp * rp), 0.0, 1.0);
}

// Refracted direction of unit `i` through unit normal `n` (facing against
// i) with the same Snell term as fresnel_dielectric, so both agree on
// where total internal reflection starts (GLSL's refract() rounds
// differently); exactly `i` at eta = 1. Zero under TIR.
vec3 refract_dir(vec3 i, vec3 n, float eta) {
    float cos_i = clamp(-dot(n, i), 0.0, 1.0);
    float cos2_t = cos2_transmitted(cos_i, eta);
    if (eta > 1.0 && cos2_t <= 0.0) return vec3(0.0);
    return eta * i + (eta * cos_i - sqrt(max(cos2_t, 0.0))) * n;
}

#endif
