// sRGB transfer function (IEC 61966-2-1, exact piecewise). Both the raster and `primary` encode albedo
// with it into a UNORM target, so both modes store identical bytes: a hardware sRGB attachment rounds
// differently (one 8-bit level on half the pixels on lavapipe).
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
