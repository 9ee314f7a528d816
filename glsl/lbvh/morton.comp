#version 460
// LBVH step 1: each triangle's 30-bit Morton code (10 bits per axis of its centroid in the centroid
// bounds) as the sort key, its number as the value.
#include "lbvh.glsl"

// The low 10 bits of v spread to every third bit.
uint spread(uint v) {
    v = (v | (v << 16u)) & 0x030000FFu;
    v = (v | (v << 8u)) & 0x0300F00Fu;
    v = (v | (v << 4u)) & 0x030C30C3u;
    v = (v | (v << 2u)) & 0x09249249u;
    return v;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    // Sum then divide, no fused operations: the host's reference computes the same bits.
    precise vec3 c = (corner(i, 0u) + corner(i, 1u) + corner(i, 2u)) / 3.0;
    precise vec3 t = (c - pc.lo) * pc.scale;
    // NaN and anything outside the bounds clamp into the grid.
    uvec3 q = uvec3(clamp(t, vec3(0.0), vec3(1023.0)));
    keys[i] = spread(q.x) << 2u | spread(q.y) << 1u | spread(q.z);
    values[i] = i;
}
