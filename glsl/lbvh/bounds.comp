#version 460
// LBVH step 4: boxes bottom up. Each leaf writes its triangle's box and climbs; at each internal node
// the first child to arrive stops and the second (which then sees both boxes) writes the union and
// goes on, so every node is written once, after its children.
#include "lbvh.glsl"

void write_box(uint node, vec3 lo, vec3 hi) {
    uint at = 6u * node;
    boxes[at] = lo.x;
    boxes[at + 1u] = lo.y;
    boxes[at + 2u] = lo.z;
    boxes[at + 3u] = hi.x;
    boxes[at + 4u] = hi.y;
    boxes[at + 5u] = hi.z;
}

void read_box(uint node, out vec3 lo, out vec3 hi) {
    uint at = 6u * node;
    lo = vec3(boxes[at], boxes[at + 1u], boxes[at + 2u]);
    hi = vec3(boxes[at + 3u], boxes[at + 4u], boxes[at + 5u]);
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= pc.count) {
        return;
    }
    uint tri = values[k];
    vec3 a = corner(tri, 0u), b = corner(tri, 1u), c = corner(tri, 2u);
    vec3 lo = min(min(a, b), c), hi = max(max(a, b), c);
    uint node = pc.count - 1u + k;
    write_box(node, lo, hi);
    memoryBarrierBuffer();
    uint p = parents[node];
    while (p != NO_PARENT) {
        // The first arrival stops (the sibling climbs on); only the second goes up, so a broken
        // hierarchy (a cycle) ends instead of hanging the device.
        if (atomicAdd(flags[p], 1u) != 1u) {
            return;
        }
        memoryBarrierBuffer();
        uvec2 ch = children[p];
        vec3 l0, h0, l1, h1;
        read_box(ch.x, l0, h0);
        read_box(ch.y, l1, h1);
        lo = min(l0, l1);
        hi = max(h0, h1);
        write_box(p, lo, hi);
        memoryBarrierBuffer();
        p = parents[p];
    }
}
