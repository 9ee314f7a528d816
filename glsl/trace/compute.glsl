// Our own two-level BVH in compute: no ray-tracing extension needed; same interface as trace/query.glsl.
// Layout (src/accel/bvh/mod.rs, compute_bvh.rs, flat.rs): static instances form ONE world-space 4-wide
// tree (header at blas_nodes[BVH_FLAT_ROOT], triangles in flat_tris), traced before the two-level BVH
// of the rest. 32-byte nodes; rigid BLASes 4-wide (compute_wide.glsl), skinned BLASes and the TLAS
// binary: count == 0 is interior (children left, left + 1), count > 0 a leaf over prims[first..+count].
#ifndef TRACE_COMPUTE_GLSL
#define TRACE_COMPUTE_GLSL
#include "../common/hit.glsl"

struct BvhNode {
    vec3 bmin;
    uint left_or_first;
    vec3 bmax;
    uint count;
};

struct BvhInstance {
    mat4 world_to_object;
    uint node_offset;  // root of this instance's BLAS in blas_nodes
    uint prim_offset;  // base of its triangle list in blas_prims
    uint mask;
    uint opaque;
    mat4 object_to_world;  // for the top level's GPU fit (anim/tlas_refit.comp)
};

layout(set = SET_TRACE, binding = BVH_BLAS_NODES, scalar) readonly buffer BlasNodes { BvhNode blas_nodes[]; };
layout(set = SET_TRACE, binding = BVH_BLAS_PRIMS, scalar) readonly buffer BlasPrims { uint blas_prims[]; };
layout(set = SET_TRACE, binding = BVH_TLAS_NODES, scalar) readonly buffer TlasNodes { BvhNode tlas_nodes[]; };
layout(set = SET_TRACE, binding = BVH_TLAS_PRIMS, scalar) readonly buffer TlasPrims { uint tlas_prims[]; };
layout(set = SET_TRACE, binding = BVH_INSTANCES, scalar) readonly buffer BvhInstances { BvhInstance bvh_instances[]; };

// World space relative to the render origin. `id`: FLAT_ID_* bits (accel/flat.rs `FlatTriangle`).
struct FlatTri {
    vec3 p0;
    vec3 p1;
    vec3 p2;
    uint id;
};
layout(set = SET_TRACE, binding = BVH_FLAT_TRIS, scalar) readonly buffer FlatTris { FlatTri flat_tris[]; };
// Per member instance, by triangle number: (first number, instance).
layout(set = SET_TRACE, binding = BVH_FLAT_MEMBERS, scalar) readonly buffer FlatMembers { uvec2 flat_members[]; };

// A flat-tree hit's instance until flat_resolve: its primitive word holds the triangle's id.
#define FLAT_HIT 0xFFFFFFFFu

// (instance, primitive) of a flat-tree hit: the last member whose first number is <= the triangle's.
// Searched once per accepted hit, not per triangle tested.
void flat_resolve(inout uint inst, inout uint prim) {
    if (inst != FLAT_HIT) return;
    uint index = prim & FLAT_ID_INDEX;
    uint lo = 0u, hi = uint(flat_members.length());
    while (hi - lo > 1u) {
        uint mid = (lo + hi) / 2u;
        if (flat_members[mid].x <= index) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    inst = flat_members[lo].y;
    prim = index - flat_members[lo].x;
}

#define BVH_STACK 32

// TRACE_STATS variants only (e.g. `bench --rays`), empty macros otherwise so normal passes pay nothing.
// In packet traversal `nodes` counts the subgroup's node visits while the ray took part, `lane_nodes`
// those the ray itself entered.
#ifdef TRACE_STATS
uint g_stat_nodes = 0u;
uint g_stat_lane_nodes = 0u;
uint g_stat_tris = 0u;
#define STAT_NODE() (g_stat_nodes++, g_stat_lane_nodes++)
#define STAT_PACKET_NODE(entered) (g_stat_nodes++, g_stat_lane_nodes += (entered) ? 1u : 0u)
#define STAT_TRI() (g_stat_tris++)
#else
#define STAT_NODE()
#define STAT_PACKET_NODE(entered)
#define STAT_TRI()
#endif

// TRACE_PACKET_SHADOW / _CLOSEST bits select subgroup-cooperative traversal (compute_packet.glsl);
// a specialization constant, so no extra shader variant.
layout(constant_id = SPEC_TRACE_PACKET) const uint TRACE_PACKET = TRACE_PACKET_DEFAULT;

// inv_d may hold +-inf. A NaN (0 * inf: origin on a slab plane, ray parallel) must not constrain the
// axis, and GLSL min/max promise nothing about NaN, so it is replaced explicitly. The exit is widened
// by 2*gamma(3) (PBRT) so a ray through a box corner or edge is not lost. Inverted (empty) boxes miss.
float ray_box(vec3 o, vec3 inv_d, float tmax, vec3 bmin, vec3 bmax) {
    if (any(greaterThan(bmin, bmax))) return 1e38;
    vec3 t0 = (bmin - o) * inv_d;
    vec3 t1 = (bmax - o) * inv_d;
    bvec3 n0 = isnan(t0), n1 = isnan(t1);
    vec3 tn = min(mix(t0, vec3(-1e38), n0), mix(t1, vec3(-1e38), n1));
    vec3 tf = max(mix(t0, vec3(1e38), n0), mix(t1, vec3(1e38), n1));
    tf += abs(tf) * 3.6e-7;
    float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float exit = min(min(tf.x, tf.y), min(tf.z, tmax));
    return enter <= exit ? enter : 1e38;
}

// Per-ray constants of the watertight test (Woop, Benthin, Wald 2013).
struct WatertightRay {
    vec3 o;
    ivec3 k;  // kx, ky, kz
    vec3 s;   // Sx, Sy, Sz
};

WatertightRay watertight_setup(vec3 o, vec3 d) {
    vec3 ad = abs(d);
    int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
    int kx = (kz + 1) % 3;
    int ky = (kx + 1) % 3;
    if (d[kz] < 0.0) { int t = kx; kx = ky; ky = t; }  // keep the winding
    WatertightRay r;
    r.o = o;
    r.k = ivec3(kx, ky, kz);
    r.s = vec3(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    return r;
}

// Returns t (or -1) and the barycentrics of vertices 1 and 2. Both windings hit.
float watertight_hit(WatertightRay r, vec3 p0, vec3 p1, vec3 p2, float tmax, out vec2 bary) {
    vec3 a = p0 - r.o, b = p1 - r.o, c = p2 - r.o;
    float ax = a[r.k.x] - r.s.x * a[r.k.z], ay = a[r.k.y] - r.s.y * a[r.k.z];
    float bx = b[r.k.x] - r.s.x * b[r.k.z], by = b[r.k.y] - r.s.y * b[r.k.z];
    float cx = c[r.k.x] - r.s.x * c[r.k.z], cy = c[r.k.y] - r.s.y * c[r.k.z];
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    // Exactly zero counts as inside for both neighbours, so a ray through a shared edge is never lost.
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return -1.0;
    float det = u + v + w;
    if (det == 0.0) return -1.0;  // degenerate or edge-on
    float t = (u * r.s.z * a[r.k.z] + v * r.s.z * b[r.k.z] + w * r.s.z * c[r.k.z]) / det;
    if (!(t > 0.0 && t < tmax)) return -1.0;
    // A zero-area triangle can pass the sign test through rounding; its normal would be zero.
    vec3 cr = cross(p1 - p0, p2 - p0);
    if (dot(cr, cr) == 0.0) return -1.0;
    bary = vec2(v, w) / det;
    return t;
}

// tl, tr >= 1e37: missed. Returns how many are hit; `far` is pushed when both are.
uint order_children(uint l, float tl, float tr, inout uint near, out uint far) {
    bool hl = tl < 1e37, hr = tr < 1e37;
    far = tl <= tr ? l + 1u : l;
    if (hl && hr) {
        near = tl <= tr ? l : l + 1u;
        return 2u;
    }
    if (hl || hr) {
        near = hl ? l : l + 1u;
        return 1u;
    }
    return 0u;
}

void object_triangle(Instance inst, uint prim, out vec3 p0, out vec3 p1, out vec3 p2) {
    uint base = inst.first_index + 3u * prim;
    p0 = vertices[inst.vertex_offset + indices[base]].position;
    p1 = vertices[inst.vertex_offset + indices[base + 1u]].position;
    p2 = vertices[inst.vertex_offset + indices[base + 2u]].position;
}

// 0 = ignore, 1 = accept. Shadow rays also fold transmittance into `tr`.
uint candidate(bool shadow, uint inst, uint prim, vec2 b, float hit_t, inout vec3 tr) {
    if (inst == FLAT_HIT) {
        if (((prim >> FLAT_ID_OPAQUE_SHIFT) & 1u) != 0u) return 1u;
        flat_resolve(inst, prim);
    }
    if (bvh_instances[inst].opaque != 0u) return 1u;
    if (!shadow) return hit_alpha_passes(inst, prim, b, hit_t) ? 1u : 0u;
    vec3 t = occluder_transmittance(inst, prim, b);
    if (all(equal(t, vec3(0.0)))) return 1u;
    tr *= t;
    return 0u;
}

// Flat-tree entries are world-space triangles with their own id (instance FLAT_HIT until resolved) and
// mask; BLAS entries are in object space (the top level already checked the mask).
void leaf_triangle(bool in_flat, Instance inst, uint inst_index, uint entry, out uint ti, out uint prim, out vec3 p0,
                   out vec3 p1, out vec3 p2, out uint tmask) {
    if (in_flat) {
        FlatTri f = flat_tris[entry];
        ti = FLAT_HIT;
        prim = f.id;
        p0 = f.p0;
        p1 = f.p1;
        p2 = f.p2;
        tmask = f.id >> FLAT_ID_MASK_SHIFT;
    } else {
        ti = inst_index;
        prim = blas_prims[entry];
        object_triangle(inst, prim, p0, p1, p2);
        tmask = 0xFFFFFFFFu;
    }
}

// The nearest accepted hit shortens tmax. True when a shadow ray is blocked.
bool test_triangle(uint inst_index, uint prim, vec3 p0, vec3 p1, vec3 p2, WatertightRay wr, bool shadow,
                   inout float tmax, inout RayHit hit, inout bool found, inout vec3 tr) {
    STAT_TRI();
    vec2 b;
    float t = watertight_hit(wr, p0, p1, p2, tmax, b);
    if (t > 0.0 && candidate(shadow, inst_index, prim, b, t, tr) == 1u) {
        tmax = t;
        hit = RayHit(inst_index, prim, b, t);
        found = true;
        return shadow;
    }
    return false;
}

// True when a shadow ray is blocked.
bool trace_leaf(bool in_flat, uint mask, Instance inst, uint inst_index, uint first, uint count, WatertightRay wr,
                bool shadow, inout float tmax, inout RayHit hit, inout bool found, inout vec3 tr) {
    for (uint i = 0u; i < count; ++i) {
        uint ti, prim, tmask;
        vec3 p0, p1, p2;
        leaf_triangle(in_flat, inst, inst_index, first + i, ti, prim, p0, p1, p2, tmask);
        if ((tmask & mask) == 0u) continue;
        if (test_triangle(ti, prim, p0, p1, p2, wr, shadow, tmax, hit, found, tr)) return true;
    }
    return false;
}

#include "compute_wide.glsl"

// Levels of the walk in trace_bvh.
#define LEVEL_FLAT 0u    // the static flat tree, 4-wide, world space
#define LEVEL_TLAS 1u    // the top level, binary, world space
#define LEVEL_WIDE 2u    // a rigid instance's 4-wide BLAS, object space
#define LEVEL_BINARY 3u  // a skinned instance's binary BLAS, object space

// One stack for every level: a BLAS's entries lie above the top level's pending ones (`floor`). At most
// BVH_STACK - 1 top-level entries under WIDE_STACK - 3 of a BLAS, so no push is ever dropped.
#define WALK_STACK (BVH_STACK + WIDE_STACK)

#define WALK_PUSH(node_, t_)                 \
    if ((t_) < 1e37 && sp < WALK_STACK) {    \
        stack[sp] = node_;                   \
        stack_t[sp++] = t_;                  \
    }

// The flat static tree, then the top level and each instance's BLAS, in ONE loop: each node test, the
// triangle test and candidate() (the material's alpha / transmittance) appear once per trace call, not
// once per level. llvmpipe's JIT time grows steeply with that code: the walk nested per level made
// the specular kernel take 32 s to compile on lavapipe (issue 41 item 7).
// Children are visited nearest first (shadow rays: farthest first, see below); pending entries keep
// their entry distance and are dropped when popped if a hit since is nearer.
bool trace_bvh(vec3 o, vec3 d, float tmax, uint mask, bool shadow, out RayHit hit, inout vec3 tr) {
    hit = RayHit(0u, 0u, vec2(0.0), tmax);
    bool found = false;
    vec3 world_inv = 1.0 / d;
    // The ray in the current level's space: world for the flat tree and the top level, object in a BLAS
    // (not renormalized, so t is the same in both spaces).
    vec3 ro = o;
    vec3 inv_d = world_inv;
    WatertightRay wr = watertight_setup(o, d);
    WideRay wr4 = wide_setup(o, inv_d);
    uint stack[WALK_STACK];
    float stack_t[WALK_STACK];
    int sp = 0;
    int floor_sp = 0;  // the current BLAS's entries start here
    uint level = LEVEL_FLAT;
    uint cur = 0u;  // wide: child code (node index or leaf); binary: node index in its buffer
    bool descend = ray_box(o, inv_d, tmax, blas_nodes[BVH_FLAT_ROOT].bmin, blas_nodes[BVH_FLAT_ROOT].bmax) < 1e37;
    uint base = (BVH_FLAT_ROOT + 1u) / 2u;  // wide: first wide node; binary BLAS: its root in blas_nodes
    uint prim_offset = 0u;
    uint inst_index = 0u;
    Instance inst = instances[0];
    uint leaf_next = 0u, leaf_end = 0u;  // the top-level leaf's instances not entered yet
    while (true) {
        if (descend) {
            descend = false;
            uint first = 0u, count = 0u;
            if (level == LEVEL_FLAT || level == LEVEL_WIDE) {
                if ((cur & BVH_WIDE_LEAF) != 0u) {
                    first = cur & 0x07FFFFFFu;
                    count = (cur >> 27) & 7u;
                } else {
                    STAT_NODE();
                    WideNode n = blas_wide[base + cur];
                    // Constant indices only (4 slots at once, a 5-exchange sorting network): llvmpipe keeps a
                    // dynamically indexed local array in memory per lane.
                    vec4 ts = wide_entries(n, wr4, tmax);
                    uint cs[4] = uint[4](n.child[0], n.child[1], n.child[2], n.child[3]);
                    // Shadow rays go farthest child first: the nearest boxes mostly hold the surface the ray
                    // leaves, grazed without a hit (Sponza: 18.9 -> 12.3 nodes, 4.6 -> 3.1 triangles per
                    // shadow ray; armadillo 4.0 -> 4.3 nodes). A shadow ray's tmax never shrinks before it
                    // stops, so the negated keys it pushes never drop a pending child.
                    if (shadow) ts = mix(vec4(1e38), -ts, lessThan(ts, vec4(1e37)));
                    WIDE_SORT2(0, 1);
                    WIDE_SORT2(2, 3);
                    WIDE_SORT2(0, 2);
                    WIDE_SORT2(1, 3);
                    WIDE_SORT2(1, 2);
                    if (ts[0] < 1e37) {
                        WALK_PUSH(cs[3], ts[3]);
                        WALK_PUSH(cs[2], ts[2]);
                        WALK_PUSH(cs[1], ts[1]);
                        cur = cs[0];
                        descend = true;
                    }
                }
            } else {
                STAT_NODE();
                bool top = level == LEVEL_TLAS;
                BvhNode n = top ? tlas_nodes[cur] : blas_nodes[base + cur];
                if (n.count > 0u) {
                    if (top) {
                        leaf_next = n.left_or_first;
                        leaf_end = leaf_next + n.count;
                    } else {
                        first = n.left_or_first;
                        count = n.count;
                    }
                } else {
                    uint l = n.left_or_first;
                    BvhNode cl = top ? tlas_nodes[l] : blas_nodes[base + l];
                    BvhNode cr = top ? tlas_nodes[l + 1u] : blas_nodes[base + l + 1u];
                    float tl = ray_box(ro, inv_d, tmax, cl.bmin, cl.bmax);
                    float tr_ = ray_box(ro, inv_d, tmax, cr.bmin, cr.bmax);
                    uint far;
                    uint visit = order_children(l, tl, tr_, cur, far);
                    if (visit == 2u) WALK_PUSH(far, max(tl, tr_));
                    descend = visit > 0u;
                }
            }
            if (count > 0u) {
                bool in_flat = level == LEVEL_FLAT;
                if (trace_leaf(in_flat, in_flat ? mask : 0xFFFFFFFFu, inst, inst_index, prim_offset + first, count,
                               wr, shadow, tmax, hit, found, tr)) {
                    return true;
                }
            }
            if (descend) continue;
        }
        // Next: a pending entry of this BLAS (or the flat tree), else the top-level leaf's next instance,
        // else a pending top-level entry.
        if (level != LEVEL_TLAS) {
            while (sp > floor_sp && stack_t[sp - 1] > tmax) --sp;
            if (sp > floor_sp) {
                cur = stack[--sp];
                descend = true;
                continue;
            }
            if (level == LEVEL_FLAT) {
                level = LEVEL_TLAS;
                cur = 0u;
                descend = tlas_nodes.length() > 0 &&
                         ray_box(o, world_inv, tmax, tlas_nodes[0].bmin, tlas_nodes[0].bmax) < 1e37;
                if (!descend) break;
                continue;
            }
        }
        if (leaf_next < leaf_end) {
            inst_index = tlas_prims[leaf_next++];
            BvhInstance bi = bvh_instances[inst_index];
            if ((bi.mask & mask) == 0u) continue;
            ro = (bi.world_to_object * vec4(o, 1.0)).xyz;
            vec3 od = mat3(bi.world_to_object) * d;
            inv_d = 1.0 / od;
            BvhNode root = blas_nodes[bi.node_offset];
            if (ray_box(ro, inv_d, tmax, root.bmin, root.bmax) > 1e37) continue;
            inst = instances[inst_index];
            wr = watertight_setup(ro, od);
            wr4 = wide_setup(ro, inv_d);
            prim_offset = bi.prim_offset;
            floor_sp = sp;
            bool wide = root.count == BVH_WIDE_HEADER;
            level = wide ? LEVEL_WIDE : LEVEL_BINARY;
            base = wide ? (bi.node_offset + 1u) / 2u : bi.node_offset;
            cur = 0u;
            descend = true;
            continue;
        }
        // Back to the top level's pending entries, in world space.
        level = LEVEL_TLAS;
        floor_sp = 0;
        ro = o;
        inv_d = world_inv;
        while (sp > 0 && stack_t[sp - 1] > tmax) --sp;
        if (sp == 0) break;
        cur = stack[--sp];
        descend = true;
    }
    return found;
}

#include "compute_packet.glsl"

// Closest hit, or (`shadow`) whether the ray is blocked, with the transmittance `tr` of what it crossed.
bool trace_ray(vec3 o, vec3 d, float tmax, bool shadow, out RayHit hit, out vec3 tr) {
    tr = vec3(1.0);
    uint mask = shadow ? MASK_SHADOW : MASK_VISIBLE;
    bool packet = (TRACE_PACKET & (shadow ? TRACE_PACKET_SHADOW : TRACE_PACKET_CLOSEST)) != 0u;
    bool found =
        packet ? trace_packet(o, d, tmax, mask, shadow, hit, tr) : trace_bvh(o, d, tmax, mask, shadow, hit, tr);
    flat_resolve(hit.instance, hit.primitive);
    return found;
}

#endif
