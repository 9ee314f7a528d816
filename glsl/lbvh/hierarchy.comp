#version 460
// LBVH step 3 (Karras 2012, "Maximizing parallelism in the construction of BVHs, octrees, and k-d
// trees"): internal node i of the count - 1 finds its key range and split from the sorted keys alone.
// Internal nodes are 0 .. count - 2 (0 the root), leaf k is node count - 1 + k. Equal keys compare by
// position, so every range splits.
#include "lbvh.glsl"

// Length of the common prefix of sorted keys a and b (positions); -1 outside the keys.
int delta(int a, int b) {
    if (b < 0 || b >= int(pc.count)) {
        return -1;
    }
    uint x = keys[a] ^ keys[b];
    if (x == 0u) {
        return 32 + 31 - findMSB(uint(a ^ b));
    }
    return 31 - findMSB(x);
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    int n = int(pc.count);
    if (i >= n - 1) {
        return;
    }
    int d = delta(i, i + 1) > delta(i, i - 1) ? 1 : -1;
    int dmin = delta(i, i - d);
    int lmax = 2;
    while (delta(i, i + lmax * d) > dmin) {
        lmax *= 2;
    }
    int l = 0;
    for (int t = lmax / 2; t >= 1; t /= 2) {
        if (delta(i, i + (l + t) * d) > dmin) {
            l += t;
        }
    }
    int j = i + l * d;
    int dnode = delta(i, j);
    int s = 0;
    for (int div = 2;; div *= 2) {
        int t = (l + div - 1) / div;
        if (delta(i, i + (s + t) * d) > dnode) {
            s += t;
        }
        if (t <= 1) {
            break;
        }
    }
    int gamma = i + s * d + min(d, 0);
    uint left = min(i, j) == gamma ? uint(n - 1 + gamma) : uint(gamma);
    uint right = max(i, j) == gamma + 1 ? uint(n - 1 + gamma + 1) : uint(gamma + 1);
    children[i] = uvec2(left, right);
    parents[left] = uint(i);
    parents[right] = uint(i);
}
