// Subgroup-cooperative ("packet") traversal, included by compute.glsl.
// Why: llvmpipe runs a subgroup as the lanes of one SIMD vector, so per-lane traversal makes every
// node fetch an 8-lane gather and every lane waits for the slowest. Here the active lanes walk ONE
// node sequence (index and stack change only through votes and broadcasts), so fetches have one
// address and the loop never diverges. Each lane tests its own ray with its own tmax; a child is
// visited if any lane that entered its parent hits it, so per-lane closest and any hit are exact.
// Stack entries keep this lane's entry distance (MISS if not hit): a lane takes part in a node only
// if it entered it and found no nearer hit since. Children are ordered along the first active lane's
// direction. Assumes the calling lanes execute together (structured control flow, uniform exits).
#ifndef TRACE_COMPUTE_PACKET_GLSL
#define TRACE_COMPUTE_PACKET_GLSL
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require

// ray_box's miss value; anything at or above MISS_BOUND is a miss.
#define MISS 1e38
#define MISS_BOUND 1e37

// Already equal in every active lane; broadcasting lets the compiler see it is uniform, so a fetch
// is one load rather than a gather.
#define SHARED(x) subgroupBroadcastFirst(x)

// Ballot-based votes: llvmpipe builds vote_any / vote_all as a loop with a branch per lane, a ballot
// as a branch-free loop of shifts and ors (gallivm lp_bld_nir_soa.c).
bool packet_any(bool c) {
    uvec4 b = subgroupBallot(c);
    return (b.x | b.y | b.z | b.w) != 0u;
}
bool packet_all(bool c) {
    return !packet_any(!c);
}

// A shared order without a cross-lane reduction per child; for coherent rays it is nearly every
// lane's own order.
float packet_key(vec3 bmin, vec3 bmax, vec3 dir) {
    return dot(bmin + bmax, dir);
}

// One fetch per triangle for all lanes, tested by the lanes that entered the leaf.
// True for a lane whose shadow ray is now blocked.
bool packet_leaf(bool in_flat, uint mask, Instance inst, uint inst_index, uint first, uint count, bool in_leaf,
                 WatertightRay wr, bool shadow, inout float tmax, inout RayHit hit, inout bool found, inout vec3 tr) {
    bool blocked = false;
    for (uint i = 0u; i < count; ++i) {
        uint ti, prim, tmask;
        vec3 p0, p1, p2;
        leaf_triangle(in_flat, inst, inst_index, first + i, ti, prim, p0, p1, p2, tmask);
        if (in_leaf && !blocked && (tmask & mask) != 0u) {
            blocked = test_triangle(ti, prim, p0, p1, p2, wr, shadow, tmax, hit, found, tr);
        }
    }
    return blocked;
}

// `in_flat` and `mask` as in trace_bvh's walk; for the lanes with `lane` set.
bool packet_blas_wide(bool in_flat, uint mask, uint inst_index, uint base, uint prim_offset, bool lane, vec3 o,
                      vec3 inv_d, vec3 dir0, WatertightRay wr, bool shadow, inout float tmax, inout RayHit hit,
                      inout vec3 tr) {
    Instance inst = instances[inst_index];
    uint stack[WIDE_STACK];
    float stack_t[WIDE_STACK];
    int sp = 0;
    uint cur = 0u;
    float cur_t = lane ? 0.0 : MISS;
    bool found = false;
    bool done = false;  // shadow ray blocked
    while (true) {
        bool in_node = !done && cur_t < MISS_BOUND && cur_t <= tmax;
        if ((cur & BVH_WIDE_LEAF) != 0u) {
            uint leaf = SHARED(cur);
            if (packet_leaf(in_flat, mask, inst, inst_index, prim_offset + (leaf & 0x07FFFFFFu), (leaf >> 27) & 7u, in_node,
                            wr, shadow, tmax, hit, found, tr)) {
                done = true;
            }
        } else {
            STAT_PACKET_NODE(in_node);
            WideNode n = blas_wide[base + SHARED(cur)];
            vec3 scale = vec3(uintBitsToFloat((n.meta & 0xFFu) << 23), uintBitsToFloat(((n.meta >> 8) & 0xFFu) << 23),
                              uintBitsToFloat(((n.meta >> 16) & 0xFFu) << 23));
            uint cnt = n.meta >> 24;
            float keys[4];  // the shared order (packet_key)
            float ts[4];    // this lane's entry distance
            uint cs[4];
            uint nh = 0u;
            for (uint i = 0u; i < cnt; ++i) {
                uint sh = 8u * i;
                vec3 qlo = vec3((n.qmin[0] >> sh) & 0xFFu, (n.qmin[1] >> sh) & 0xFFu, (n.qmin[2] >> sh) & 0xFFu);
                vec3 qhi = vec3((n.qmax[0] >> sh) & 0xFFu, (n.qmax[1] >> sh) & 0xFFu, (n.qmax[2] >> sh) & 0xFFu);
                vec3 lo = n.origin + qlo * scale, hi = n.origin + qhi * scale;
                float t = in_node ? ray_box(o, inv_d, tmax, lo, hi) : MISS;
                if (packet_any(t < MISS_BOUND)) {
                    float k = packet_key(lo, hi, dir0);
                    uint j = nh;
                    while (j > 0u && keys[j - 1u] > k) {
                        keys[j] = keys[j - 1u];
                        ts[j] = ts[j - 1u];
                        cs[j] = cs[j - 1u];
                        --j;
                    }
                    keys[j] = k;
                    ts[j] = t;
                    cs[j] = n.child[i];
                    ++nh;
                }
            }
            if (nh > 0u) {
                for (uint j = nh - 1u; j > 0u; --j) {
                    if (sp < WIDE_STACK) {
                        stack[sp] = cs[j];
                        stack_t[sp++] = ts[j];
                    }
                }
                cur = cs[0];
                cur_t = ts[0];
                continue;
            }
        }
        if (shadow && packet_all(done)) break;
        while (sp > 0 && packet_all(done || stack_t[sp - 1] >= MISS_BOUND || stack_t[sp - 1] > tmax)) --sp;
        if (sp == 0) break;
        cur = stack[--sp];
        cur_t = stack_t[sp];
    }
    return found;
}

// A binary (skinned, refitted) BLAS, one lane on its own; the caller tested the root. Ray in object space.
bool lane_blas_binary(uint inst_index, vec3 o, vec3 d, bool shadow, inout float tmax, inout RayHit hit,
                      inout vec3 tr) {
    BvhInstance bi = bvh_instances[inst_index];
    Instance inst = instances[inst_index];
    vec3 inv_d = 1.0 / d;
    WatertightRay wr = watertight_setup(o, d);
    uint stack[BVH_STACK];
    int sp = 0;
    uint node = 0u;
    bool found = false;
    while (true) {
        STAT_NODE();
        BvhNode n = blas_nodes[bi.node_offset + node];
        if (n.count > 0u) {
            if (trace_leaf(false, 0xFFFFFFFFu, inst, inst_index, bi.prim_offset + n.left_or_first, n.count, wr, shadow,
                           tmax, hit, found, tr)) {
                return true;
            }
        } else {
            uint l = n.left_or_first;
            BvhNode cl = blas_nodes[bi.node_offset + l];
            BvhNode cr = blas_nodes[bi.node_offset + l + 1u];
            uint far;
            uint visit = order_children(l, ray_box(o, inv_d, tmax, cl.bmin, cl.bmax),
                                        ray_box(o, inv_d, tmax, cr.bmin, cr.bmax), node, far);
            if (visit == 2u && sp < BVH_STACK) stack[sp++] = far;
            if (visit > 0u) continue;
        }
        if (sp == 0) break;
        node = stack[--sp];
    }
    return found;
}

// The instance is the same in every lane; the ray is each lane's, in object space.
bool packet_blas(uint inst_index, bool lane, vec3 o, vec3 d, bool shadow, inout float tmax, inout RayHit hit,
                 inout vec3 tr) {
    BvhInstance bi = bvh_instances[inst_index];
    vec3 inv_d = 1.0 / d;
    BvhNode root = blas_nodes[bi.node_offset];
    lane = lane && ray_box(o, inv_d, tmax, root.bmin, root.bmax) < MISS_BOUND;
    if (!packet_any(lane)) return false;
    if (root.count == BVH_WIDE_HEADER) {
        WatertightRay wr = watertight_setup(o, d);
        return packet_blas_wide(false, 0xFFFFFFFFu, inst_index, (bi.node_offset + 1u) / 2u, bi.prim_offset, lane, o,
                                inv_d, subgroupBroadcastFirst(d), wr, shadow, tmax, hit, tr);
    }
    // A binary (skinned, refitted) BLAS: each lane on its own.
    return lane && lane_blas_binary(inst_index, o, d, shadow, tmax, hit, tr);
}

bool trace_packet(vec3 o, vec3 d, float tmax, uint mask, bool shadow, out RayHit hit, inout vec3 tr) {
    vec3 inv_d = 1.0 / d;
    uint stack[BVH_STACK];
    float stack_t[BVH_STACK];
    int sp = 0;
    uint node = 0u;
    hit = RayHit(0u, 0u, vec2(0.0), tmax);
    BvhNode froot = blas_nodes[BVH_FLAT_ROOT];
    bool flat_lane = ray_box(o, inv_d, tmax, froot.bmin, froot.bmax) < MISS_BOUND;
    bool found = packet_any(flat_lane) &&
                 packet_blas_wide(true, mask, 0u, (BVH_FLAT_ROOT + 1u) / 2u, 0u, flat_lane, o, inv_d,
                                  subgroupBroadcastFirst(d), watertight_setup(o, d), shadow, tmax, hit, tr);
    bool done = shadow && found;
    if (tlas_nodes.length() == 0) return found;
    float cur_t = done ? MISS : ray_box(o, inv_d, tmax, tlas_nodes[0].bmin, tlas_nodes[0].bmax);
    if (packet_all(cur_t >= MISS_BOUND)) return found;
    vec3 dir0 = subgroupBroadcastFirst(d);
    while (true) {
        bool in_node = !done && cur_t < MISS_BOUND && cur_t <= tmax;
        STAT_PACKET_NODE(in_node);
        BvhNode n = tlas_nodes[SHARED(node)];
        if (n.count > 0u) {
            for (uint i = 0u; i < n.count; ++i) {
                uint inst = SHARED(tlas_prims[n.left_or_first + i]);
                BvhInstance bi = bvh_instances[inst];
                bool lane = in_node && !done && (bi.mask & mask) != 0u;
                if (!packet_any(lane)) continue;
                // Not renormalized, so t is the same in both spaces.
                vec3 oo = (bi.world_to_object * vec4(o, 1.0)).xyz;
                vec3 od = mat3(bi.world_to_object) * d;
                if (packet_blas(inst, lane, oo, od, shadow, tmax, hit, tr)) {
                    found = true;
                    if (shadow) done = true;
                }
            }
        } else {
            uint l = n.left_or_first;
            BvhNode cl = tlas_nodes[l], cr = tlas_nodes[l + 1u];
            float tl = in_node ? ray_box(o, inv_d, tmax, cl.bmin, cl.bmax) : MISS;
            float tr_ = in_node ? ray_box(o, inv_d, tmax, cr.bmin, cr.bmax) : MISS;
            bool hl = packet_any(tl < MISS_BOUND), hr = packet_any(tr_ < MISS_BOUND);
            if (hl || hr) {
                bool left_first = hl && (!hr || packet_key(cl.bmin, cl.bmax, dir0) <= packet_key(cr.bmin, cr.bmax, dir0));
                if (hl && hr && sp < BVH_STACK) {
                    stack[sp] = left_first ? l + 1u : l;
                    stack_t[sp++] = left_first ? tr_ : tl;
                }
                node = left_first ? l : l + 1u;
                cur_t = left_first ? tl : tr_;
                continue;
            }
        }
        if (shadow && packet_all(done)) break;
        while (sp > 0 && packet_all(done || stack_t[sp - 1] >= MISS_BOUND || stack_t[sp - 1] > tmax)) --sp;
        if (sp == 0) break;
        node = stack[--sp];
        cur_t = stack_t[sp];
    }
    return found;
}

#endif
