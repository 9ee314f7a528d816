// The sRGB transfer function, both ways (IEC 61966-2-1, exact piecewise
// form). The G-buffer's albedo target is UNORM holding sRGB-encoded values
// written by these functions in both the raster (`gbuffer`) and the
// ray-traced (`primary`) pass, so the two modes store identical bytes: a
// hardware sRGB attachment and a shader encode round differently (one
// 8-bit level on half the pixels on lavapipe).
#ifndef SRGB_GLSL
#define SRGB_GLSL

vec3 srgb_encode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

vec3 srgb_decode(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

#endif
