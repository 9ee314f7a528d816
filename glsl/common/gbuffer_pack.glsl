// How the G-buffer stores a unit normal: octahedral mapping (Cigolle et
// al., "A Survey of Efficient Representations for Independent Unit
// Vectors", JCGT 2014) quantized to two 16-bit snorms in one uint. Max
// angular error 0.0036 degrees (tests/render/shading_closed_form.rs), a quarter
// of the bytes of the rgba16f vector it replaced. Written by gbuffer_resolve.comp
// and the `primary` pass, read by gbuffer_read.glsl and the edge AA.
#ifndef GBUFFER_PACK_GLSL
#define GBUFFER_PACK_GLSL

vec2 oct_sign(vec2 v) {
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

// Any non-zero `n` (normalised here); zero maps to +Z.
uint oct_encode(vec3 n) {
    float l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if (!(l1 > 0.0)) return packSnorm2x16(vec2(0.0));
    vec2 p = n.xy / l1;
    if (n.z < 0.0) p = (1.0 - abs(p.yx)) * oct_sign(p);
    return packSnorm2x16(p);
}

vec3 oct_decode(uint bits) {
    vec2 p = unpackSnorm2x16(bits);
    vec3 n = vec3(p, 1.0 - abs(p.x) - abs(p.y));
    // Lower hemisphere: fold the corners back (t <= 0 there).
    float t = max(-n.z, 0.0);
    n.xy -= t * oct_sign(n.xy);
    return normalize(n);
}

#endif
