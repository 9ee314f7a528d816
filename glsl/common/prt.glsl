// Diffuse PRT at a primary hit (scene/prt; layout SCENE_PRT): vertex transfer vectors interpolated by
// barycentrics, dotted with Frame.sh_radiance (rotated and scaled on the host). The transfer holds
// the clamped cosine (and visibility, interreflection), so the result is the irradiance E.
#ifndef PRT_GLSL
#define PRT_GLSL
#include "scene.glsl"

float prt_float(uint word) {
    return uintBitsToFloat(prt_data[word]);
}

// False (e = 0) without FRAME_AMBIENT_PRT or without transfer (animated, skinned).
bool prt_irradiance(uint instance, uint primitive, vec2 b, out vec3 e) {
    e = vec3(0.0);
    if ((frame.flags & FRAME_AMBIENT_PRT) == 0u || instance >= prt_data[2]) return false;
    uint first = prt_data[PRT_HEADER_WORDS + instance];
    if (first == PRT_NO_VERTEX) return false;
    uint coeffs = min(prt_data[0], SH_PRT_MAX_COEFFS);
    uint channels = prt_data[1];
    uint base = PRT_HEADER_WORDS + prt_data[2];
    uint tri = instances[instance].first_index + 3u * primitive;
    float w[3] = float[](1.0 - b.x - b.y, b.x, b.y);
    for (uint j = 0u; j < 3u; j++) {
        uint at = base + (first + indices[tri + j]) * coeffs * channels;
        for (uint k = 0u; k < coeffs; k++) {
            uint c = at + k * channels;
            vec3 t = channels == 3u ? vec3(prt_float(c), prt_float(c + 1u), prt_float(c + 2u)) : vec3(prt_float(c));
            e += w[j] * t * frame.sh_radiance[k].rgb;
        }
    }
    // Ringing of a truncated SH product can dip below 0.
    e = max(e, vec3(0.0));
    return true;
}

#endif
