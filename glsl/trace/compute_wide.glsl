// 4-wide BLAS traversal for the compute tracer (included by compute.glsl,
// which defines ray_box, trace_leaf and the types).
// Layout: src/accel/bvh/wide.rs. A static BLAS's binary node at its node
// offset is a header (root bounds, count == BVH_WIDE_HEADER); the 64-byte
// wide nodes follow at the next (even) 32-byte slot, so wide node j is
// blas_wide[(node_offset + 1) / 2 + j]: the same buffer, read as 64-byte
// records.
#ifndef TRACE_COMPUTE_WIDE_GLSL
#define TRACE_COMPUTE_WIDE_GLSL

struct WideNode {
    vec3 origin;     // quantization origin
    uint meta;       // exponent byte per axis (biased by 127), child count << 24
    uint qmin[3];    // per axis: child i's low corner byte at bits 8i..8i+7
    uint qmax[3];
    uint child[4];   // wide node index, or BVH_WIDE_LEAF | count << 27 | first
    uint pad0;
    uint pad1;
};

layout(set = SET_TRACE, binding = BVH_BLAS_NODES, scalar) readonly buffer BlasWideNodes { WideNode blas_wide[]; };

// Pending children: at most 3 per wide level, and a wide tree is no deeper
// than its binary source (MAX_DEPTH = 32 levels): 3 * 31 < 96, so no push is
// ever dropped.
#define WIDE_STACK 96

// Compare-exchange of slots a < b (constants) by entry distance.
#define WIDE_SORT2(a, b)                                 \
    if (ts[b] < ts[a]) {                                 \
        float t_ = ts[a];                                \
        ts[a] = ts[b];                                   \
        ts[b] = t_;                                      \
        uint c_ = cs[a];                                 \
        cs[a] = cs[b];                                   \
        cs[b] = c_;                                      \
    }

// Closest hit (any opaque hit for shadow rays) in the wide tree at
// blas_wide[base...]: hit children sorted by entry distance, the nearest
// visited next, the others pushed far to near with their entry distance, and
// dropped when popped if a hit found since is nearer. `in_flat`: the flat static
// tree (leaves index flat_tris; `mask` filters its triangles); otherwise
// instance `inst_index`'s BLAS.
bool trace_blas_wide(bool in_flat, uint mask, uint inst_index, uint base, uint prim_offset, vec3 o, vec3 inv_d,
                     WatertightRay wr, bool shadow, inout float tmax, inout RayHit hit, inout vec3 tr) {
    Instance inst = instances[inst_index];
    uint stack[WIDE_STACK];
    float stack_t[WIDE_STACK];  // entry distance: skipped once a hit is nearer
    int sp = 0;
    uint cur = 0u;
    bool found = false;
    while (true) {
        if ((cur & BVH_WIDE_LEAF) != 0u) {
            uint first = cur & 0x07FFFFFFu;
            uint count = (cur >> 27) & 7u;
            if (trace_leaf(in_flat, mask, inst, inst_index, prim_offset + first, count, wr, shadow, tmax, hit, found, tr)) {
                return true;
            }
        } else {
            STAT_NODE();
            WideNode n = blas_wide[base + cur];
            // 2^(byte - 127) from its bits: exact, like the host's decode.
            vec3 scale = vec3(uintBitsToFloat((n.meta & 0xFFu) << 23), uintBitsToFloat(((n.meta >> 8) & 0xFFu) << 23),
                              uintBitsToFloat(((n.meta >> 16) & 0xFFu) << 23));
            uint cnt = n.meta >> 24;
            // All 4 slots with constant indices (missing children miss), then
            // a 5-exchange sorting network: no dynamically indexed local
            // array, which llvmpipe would keep in memory per lane.
            float ts[4];
            uint cs[4];
            for (uint i = 0u; i < 4u; ++i) {
                uint sh = 8u * i;
                vec3 qlo = vec3((n.qmin[0] >> sh) & 0xFFu, (n.qmin[1] >> sh) & 0xFFu, (n.qmin[2] >> sh) & 0xFFu);
                vec3 qhi = vec3((n.qmax[0] >> sh) & 0xFFu, (n.qmax[1] >> sh) & 0xFFu, (n.qmax[2] >> sh) & 0xFFu);
                ts[i] = i < cnt ? ray_box(o, inv_d, tmax, n.origin + qlo * scale, n.origin + qhi * scale) : 1e38;
                cs[i] = n.child[i];
            }
            WIDE_SORT2(0, 1);
            WIDE_SORT2(2, 3);
            WIDE_SORT2(0, 2);
            WIDE_SORT2(1, 3);
            WIDE_SORT2(1, 2);
            if (ts[0] < 1e37) {
                for (int j = 3; j > 0; --j) {
                    if (ts[j] < 1e37 && sp < WIDE_STACK) {
                        stack[sp] = cs[j];
                        stack_t[sp++] = ts[j];
                    }
                }
                cur = cs[0];
                continue;
            }
        }
        while (sp > 0 && stack_t[sp - 1] > tmax) --sp;
        if (sp == 0) break;
        cur = stack[--sp];
    }
    return found;
}

#endif
