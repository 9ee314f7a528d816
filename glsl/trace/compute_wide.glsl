// 4-wide BLAS traversal, included by compute.glsl. Layout: src/accel/bvh/wide.rs. A static BLAS's
// binary node at its offset is a header (root bounds, count == BVH_WIDE_HEADER); the 64-byte wide
// nodes follow at the next even 32-byte slot: wide node j is blas_wide[(node_offset + 1) / 2 + j].
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

// At most 3 pushes per wide level, no deeper than the binary source (MAX_DEPTH 32): 3 * 31 < 96,
// so no push is ever dropped.
#define WIDE_STACK 96

// Compare-exchange of constant slots a < b by entry distance.
#define WIDE_SORT2(a, b)                                 \
    if (ts[b] < ts[a]) {                                 \
        float t_ = ts[a];                                \
        ts[a] = ts[b];                                   \
        ts[b] = t_;                                      \
        uint c_ = cs[a];                                 \
        cs[a] = cs[b];                                   \
        cs[b] = c_;                                      \
    }

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

// A macro, not a loop over k: every index stays a compile-time constant.
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

// Entry distance of node n's 4 child boxes (1e38: missed or absent), one slab test per axis in the
// quantized frame: a plane is at a + q * b with a, b once per node, and the sign of inv picks the near
// byte, so no min/max per plane. Rounding (u = 2^-24): a is off by 2u|origin - o||inv|, the host's
// conservative decode by u|origin + q s||inv|, q * b + a by u(|q b| + |t|); w bounds the first three,
// the exit's relative widening (as in ray_box) the last. A (nearly) parallel axis constrains nothing.
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

#endif
