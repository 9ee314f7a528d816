// Background for missed camera rays and radiance of missed secondary rays.
#ifndef ENV_GLSL
#define ENV_GLSL
#include "scene.glsl"
#include "math.glsl"

// Equirectangular: +Y up, u = 0.5 looks down -Z, rotation turns about +Y.
vec2 env_uv(vec3 d) {
    float phi = atan(d.x, -d.z) + frame.env_rotation;
    float u = phi / (2.0 * PI) + 0.5;
    float v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return vec2(u, v);
}

vec3 environment(vec3 dir) {
    if (frame.has_env_map != 0u) {
        return textureLod(env_map, env_uv(dir), 0.0).rgb * frame.env_intensity;
    }
    return frame.env_color * frame.env_intensity;
}

// E(n) = ∫ L(w) max(0, n·w) dw from 3-band SH (scene/sh/basis.rs, in its frame x = -n.z, y = n.x,
// z = n.y: the map's own angles). The Hann window keeps it non-negative on the shipped maps
// (tests/render/ibl.rs) but not everywhere (one bright cap on black dips to -0.3% opposite), hence
// the clamp: a negative pixel would poison the log-average exposure.
vec3 sh_irradiance(vec3 n) {
    float x = -n.z, y = n.x, z = n.y;
    const float c0 = 0.5 / sqrt(PI);
    const float c1 = sqrt(3.0 / (4.0 * PI));
    const float c2 = 0.5 * sqrt(15.0 / PI);
    const float c20 = 0.25 * sqrt(5.0 / PI);
    const float c22 = 0.25 * sqrt(15.0 / PI);
    float b[SH_IRRADIANCE_COEFFS] = float[](
        c0,
        -c1 * y, c1 * z, -c1 * x,
        c2 * x * y, -c2 * y * z, c20 * (3.0 * z * z - 1.0), -c2 * x * z, c22 * (x * x - y * y));
    vec3 e = vec3(0.0);
    for (uint i = 0u; i < SH_IRRADIANCE_COEFFS; i++) {
        e += frame.sh_irradiance[i].rgb * b[i];
    }
    return max(e, vec3(0.0));
}

// What a Lambertian surface of albedo 1 exits, unshadowed: E(n) / pi with FRAME_AMBIENT_SH, else the
// map's mean radiance (or the constant colour: E = pi L).
vec3 ambient_radiance(vec3 n) {
    if ((frame.flags & FRAME_AMBIENT_SH) != 0u) {
        return sh_irradiance(n) / PI;
    }
    return frame.env_ambient;
}

#endif
