// Tone curves: exposed linear radiance -> display-referred [0, 1], before
// sRGB encoding. Every curve maps 0 to 0 and is non-decreasing (tested
// through the shading probe, tests/render/tonemap.rs).
#ifndef TONEMAP_GLSL
#define TONEMAP_GLSL

float tone_luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// Keeps chroma. ld is capped far above white so the ratio stays finite and a zero channel stays zero.
vec3 tone_scale(vec3 c, float l, float ld) {
    return l > 0.0 ? c * (min(ld, 64.0) / l) : vec3(0.0);
}

// Reinhard et al. 2002, Equation 3 on luminance.
vec3 tonemap_reinhard(vec3 c) {
    float l = tone_luminance(c);
    return tone_scale(c, l, l / (1.0 + l));
}

// Reinhard et al. 2002, Equation 4: luminance `white` (and above) maps to 1.
vec3 tonemap_reinhard_white(vec3 c, float white) {
    float l = tone_luminance(c);
    float w2 = max(white * white, 1e-8);
    return tone_scale(c, l, l * (1.0 + l / w2) / (1.0 + l));
}

// Narkowicz 2015: rational fit of the ACES RRT + ODT, per channel; input scaled by 0.6 so key-0.18
// exposure lands mid-curve as in ACES.
vec3 tonemap_aces(vec3 c) {
    vec3 x = c * 0.6;
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

// `op` is a TONEMAP_* code; `white` is used by TONEMAP_REINHARD_WHITE.
// Input: finite, non-negative, exposed radiance. Output in [0, 1].
vec3 tonemap_apply(uint op, vec3 c, float white) {
    vec3 o;
    if (op == TONEMAP_REINHARD_WHITE) {
        o = tonemap_reinhard_white(c, white);
    } else if (op == TONEMAP_ACES) {
        o = tonemap_aces(c);
    } else if (op == TONEMAP_NONE) {
        o = c;
    } else {
        o = tonemap_reinhard(c);
    }
    return clamp(o, 0.0, 1.0);
}

#endif
