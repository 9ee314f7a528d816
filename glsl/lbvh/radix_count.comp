#version 460
// LBVH sort, pass part 1: per block of LBVH_RADIX_BLOCK keys (one invocation each, in key order), how
// many have each digit. hist[digit * blocks + block]: digit-major, so one exclusive scan gives every
// key's destination.
#include "lbvh.glsl"

void main() {
    uint b = gl_GlobalInvocationID.x;
    if (b >= pc.blocks) {
        return;
    }
    uint counts[RADIX];
    for (uint d = 0u; d < RADIX; d++) {
        counts[d] = 0u;
    }
    uint end = min(pc.count, (b + 1u) * LBVH_RADIX_BLOCK);
    for (uint j = b * LBVH_RADIX_BLOCK; j < end; j++) {
        counts[(keys[j] >> pc.shift) & (RADIX - 1u)]++;
    }
    for (uint d = 0u; d < RADIX; d++) {
        hist[d * pc.blocks + b] = counts[d];
    }
}
