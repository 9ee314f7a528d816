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

// Compare-exchange of slots a < b (constants) by sort key (entry distance).
#define WIDE_SORT2(a, b)                                 \
    if (ts[b] < ts[a]) {                                 \
        float t_ = ts[a];                                \
        ts[a] = ts[b];                                   \
        ts[b] = t_;                                      \
        uint c_ = cs[a];                                 \
        cs[a] = cs[b];                                   \
        cs[b] = c_;                                      \
    }

// Per-ray constants of the wide node test (wide_entries).
struct WideRay {
    vec3 o;
    vec3 inv;   // 1 / d; 0 on an axis the ray is parallel to
    vec3 err;   // WIDE_ERR * |inv|: scales each node's rounding bound
    vec3 ao;    // |o|
    bvec3 par;  // |d| < 1e-20 (|inv_d| > 1e20 or inf): no slab on this axis
    bvec3 neg;  // inv < 0: the high plane is entered first
};

// 6 unit roundoffs (2^-24): covers the roundings bounded in wide_entries.
#define WIDE_ERR 3.6e-7

WideRay wide_setup(vec3 o, vec3 inv_d) {
    WideRay r;
    r.o = o;
    r.par = greaterThan(abs(inv_d), vec3(1e20));
    r.inv = mix(inv_d, vec3(0.0), r.par);
    r.err = WIDE_ERR * abs(r.inv);
    r.ao = abs(o);
    r.neg = lessThan(r.inv, vec3(0.0));
    return r;
}

// One axis of wide_entries: `k` the axis index, `c` its swizzle (a macro,
// not a loop over k: every index stays a constant for the compiler).
#define WIDE_AXIS(k, c)                                                                      \
    {                                                                                        \
        float s = uintBitsToFloat(((n.meta >> (8 * k)) & 0xFFu) << 23); /* 2^(byte-127) */   \
        float a = (n.origin.c - r.o.c) * r.inv.c;                                            \
        float b = s * r.inv.c;                                                               \
        float w = r.err.c * (abs(n.origin.c) + r.ao.c + 256.0 * s);                          \
        float an = r.par.c ? -1e38 : a - w;                                                  \
        float af = r.par.c ? 1e38 : a + w;                                                   \
        vec4 qn = vec4((uvec4(r.neg.c ? n.qmax[k] : n.qmin[k]) >> sh) & 0xFFu);              \
        vec4 qf = vec4((uvec4(r.neg.c ? n.qmin[k] : n.qmax[k]) >> sh) & 0xFFu);              \
        tn = max(tn, qn * b + an);                                                           \
        tf = min(tf, qf * b + af);                                                           \
    }

// Entry distance of each of node n's 4 child boxes (1e38: missed, or no such
// child): one slab test over the 4 children per axis, in the quantized
// frame. A child plane's distance is (origin + q * s - o) * inv = a + q * b
// with a = (origin - o) * inv and b = s * inv computed once per node, so a
// plane costs one multiply-add; the sign of inv picks which byte is the near
// plane, so no min/max per plane. Rounding: a is off by 2u|origin - o||inv|,
// the host's decode (the box it proved conservative) by u|origin + q s||inv|,
// q * b + a by u(|q b| + |t|) (u = 2^-24); w (WIDE_AXIS) bounds the first
// three, the exit's relative widening (as in ray_box) the last. A (nearly)
// parallel axis constrains nothing: conservative, and no 0 * inf.
vec4 wide_entries(WideNode n, WideRay r, float tmax) {
    const uvec4 sh = uvec4(0u, 8u, 16u, 24u);
    vec4 tn = vec4(0.0);
    vec4 tf = vec4(1e38);
    WIDE_AXIS(0, x)
    WIDE_AXIS(1, y)
    WIDE_AXIS(2, z)
    tf = min(tf + abs(tf) * WIDE_ERR, vec4(tmax));
    bvec4 hit = lessThanEqual(tn, tf);
    bvec4 present = lessThan(uvec4(0u, 1u, 2u, 3u), uvec4(n.meta >> 24));
    return mix(vec4(1e38), tn, bvec4(uvec4(hit) & uvec4(present)));
}

// Push slot j (a constant) of the sorted children if it was hit.
#define WIDE_PUSH(j)                            \
    if (ts[j] < 1e37 && sp < WIDE_STACK) {      \
        stack[sp] = cs[j];                      \
        stack_t[sp++] = ts[j];                  \
    }

// Closest hit (any opaque hit for shadow rays) in the wide tree at
// blas_wide[base...]: hit children sorted by entry distance, the nearest
// (shadow rays: the farthest) visited next, the others pushed in reverse
// order with their sort key, and dropped when popped if a hit found since is
// nearer. `in_flat`: the flat static
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
    WideRay wr4 = wide_setup(o, inv_d);
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
            // Constant indices throughout (the 4 slots at once, then a
            // 5-exchange sorting network): no dynamically indexed local
            // array, which llvmpipe would keep in memory per lane.
            vec4 ts = wide_entries(n, wr4, tmax);
            uint cs[4] = uint[4](n.child[0], n.child[1], n.child[2], n.child[3]);
            // Shadow rays: farthest child first. Any blocking hit ends the
            // ray, so the order only decides how soon one is found; the
            // nearest boxes of a ray leaving a surface hold mostly that
            // surface's surroundings, which it grazes without hitting
            // (measured on Sponza: 18.9 -> 12.3 nodes and 4.6 -> 3.1
            // triangles per shadow ray; the armadillo view: 4.0 -> 4.3
            // nodes). Sorting the negated entry distances does it; a shadow
            // ray's tmax never shrinks before it stops, so the negated
            // distances it pushes never drop a pending child.
            if (shadow) ts = mix(vec4(1e38), -ts, lessThan(ts, vec4(1e37)));
            WIDE_SORT2(0, 1);
            WIDE_SORT2(2, 3);
            WIDE_SORT2(0, 2);
            WIDE_SORT2(1, 3);
            WIDE_SORT2(1, 2);
            if (ts[0] < 1e37) {
                WIDE_PUSH(3);
                WIDE_PUSH(2);
                WIDE_PUSH(1);
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
