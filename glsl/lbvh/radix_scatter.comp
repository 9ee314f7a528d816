#version 460
// LBVH sort, pass part 3: each block's keys, in order, to their digit's next slot (stable, so the
// passes compose into a sort by the whole key with ties in input order).
#include "lbvh.glsl"

void main() {
    uint b = gl_GlobalInvocationID.x;
    if (b >= pc.blocks) {
        return;
    }
    uint next[RADIX];
    for (uint d = 0u; d < RADIX; d++) {
        next[d] = hist[d * pc.blocks + b];
    }
    uint end = min(pc.count, (b + 1u) * LBVH_RADIX_BLOCK);
    for (uint j = b * LBVH_RADIX_BLOCK; j < end; j++) {
        uint k = keys[j];
        uint d = (k >> pc.shift) & (RADIX - 1u);
        keys_out[next[d]] = k;
        values_out[next[d]] = values[j];
        next[d]++;
    }
}
