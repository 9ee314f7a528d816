#version 460
// Pass `fxaa`: FXAA 3.11 quality preset (T. Lottes, 2011). Luma from sRGB-encoded values because
// FXAA's thresholds are perceptual. Low-contrast or zero-offset pixels are copied unchanged.
#include "common/scene.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = AA_IN, rgba8) uniform readonly image2D ldr_in;
layout(set = SET_PASS, binding = AA_OUT, rgba8) uniform writeonly image2D ldr_out;

// FXAA 3.11's "quality" defaults.
const float CONTRAST_MIN = 0.0312;
const float CONTRAST_REL = 0.125;
const float SUBPIXEL = 0.75;
// Longer steps far out: 12 steps reach 26 pixels each way.
const int SEARCH_STEPS = 12;
const float STEP[SEARCH_STEPS] = float[](1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0);

vec3 fetch(ivec2 p) {
    return imageLoad(ldr_in, clamp(p, ivec2(0), ivec2(frame.resolution) - 1)).rgb;
}

float luma(vec3 c) {
    return dot(c, vec3(0.299, 0.587, 0.114));
}

// By hand (pixel units, centres at +0.5, edges clamped) so every device filters alike.
vec3 bilinear(vec2 pos) {
    vec2 p = pos - 0.5;
    vec2 f = p - floor(p);
    ivec2 i = ivec2(floor(p));
    vec3 top = mix(fetch(i), fetch(i + ivec2(1, 0)), f.x);
    vec3 bottom = mix(fetch(i + ivec2(0, 1)), fetch(i + ivec2(1, 1)), f.x);
    return mix(top, bottom, f.y);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    vec4 centre = imageLoad(ldr_in, px);
    float lc = luma(centre.rgb);
    float ln = luma(fetch(px + ivec2(0, -1)));
    float ls = luma(fetch(px + ivec2(0, 1)));
    float lw = luma(fetch(px + ivec2(-1, 0)));
    float le = luma(fetch(px + ivec2(1, 0)));
    float lmax = max(lc, max(max(ln, ls), max(lw, le)));
    float lmin = min(lc, min(min(ln, ls), min(lw, le)));
    float range = lmax - lmin;
    if (range < max(CONTRAST_MIN, lmax * CONTRAST_REL)) {
        imageStore(ldr_out, px, centre);
        return;
    }
    float lnw = luma(fetch(px + ivec2(-1, -1)));
    float lne = luma(fetch(px + ivec2(1, -1)));
    float lsw = luma(fetch(px + ivec2(-1, 1)));
    float lse = luma(fetch(px + ivec2(1, 1)));

    // A horizontal edge changes luma down the columns.
    float horizontal = abs(lnw + lsw - 2.0 * lw) + 2.0 * abs(ln + ls - 2.0 * lc) + abs(lne + lse - 2.0 * le);
    float vertical = abs(lnw + lne - 2.0 * ln) + 2.0 * abs(lw + le - 2.0 * lc) + abs(lsw + lse - 2.0 * ls);
    bool horz = horizontal >= vertical;
    // The edge lies towards the neighbour across it with the larger step.
    float l_neg = horz ? ln : lw;
    float l_pos = horz ? ls : le;
    bool neg = abs(l_neg - lc) >= abs(l_pos - lc);
    float l_other = neg ? l_neg : l_pos;
    float gradient = abs(l_other - lc);
    vec2 across = (horz ? vec2(0.0, 1.0) : vec2(1.0, 0.0)) * (neg ? -1.0 : 1.0);
    vec2 along = horz ? vec2(1.0, 0.0) : vec2(0.0, 1.0);

    // Search along the line between this pixel and the one across (bilinear: the two rows' mean) until
    // luma leaves the edge's average by a quarter of its gradient.
    float edge_luma = 0.5 * (lc + l_other);
    float threshold = 0.25 * gradient;
    vec2 start = vec2(px) + 0.5 + 0.5 * across;
    vec2 p1 = start - along * STEP[0];
    vec2 p2 = start + along * STEP[0];
    float e1 = luma(bilinear(p1)) - edge_luma;
    float e2 = luma(bilinear(p2)) - edge_luma;
    bool end1 = abs(e1) >= threshold;
    bool end2 = abs(e2) >= threshold;
    for (int i = 1; i < SEARCH_STEPS && !(end1 && end2); i++) {
        if (!end1) {
            p1 -= along * STEP[i];
            e1 = luma(bilinear(p1)) - edge_luma;
            end1 = abs(e1) >= threshold;
        }
        if (!end2) {
            p2 += along * STEP[i];
            e2 = luma(bilinear(p2)) - edge_luma;
            end2 = abs(e2) >= threshold;
        }
    }
    float d1 = dot(start - p1, along);
    float d2 = dot(p2 - start, along);
    bool nearer1 = d1 < d2;
    float dist = min(d1, d2);
    // Only the pixel on the side the nearer end bends away from moves (else the other side's does).
    bool centre_darker = lc < edge_luma;
    bool bends = ((nearer1 ? e1 : e2) < 0.0) != centre_darker;
    float edge_offset = bends ? 0.5 - dist / (d1 + d2) : 0.0;

    // Sub-pixel aliasing (a thin line, a dot) blends too.
    float mean = (2.0 * (ln + ls + lw + le) + lnw + lne + lsw + lse) / 12.0;
    float s = clamp(abs(mean - lc) / range, 0.0, 1.0);
    s = (3.0 - 2.0 * s) * s * s;
    float sub_offset = s * s * SUBPIXEL;

    float offset = max(edge_offset, sub_offset);
    if (!(offset > 0.0)) {
        imageStore(ldr_out, px, centre);
        return;
    }
    vec3 c = bilinear(vec2(px) + 0.5 + across * offset);
    imageStore(ldr_out, px, vec4(c, centre.a));
}
