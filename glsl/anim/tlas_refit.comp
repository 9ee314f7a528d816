#version 460
// Top-level refit on the GPU after the skinned BLAS refit (bvh_refit.comp) in the same command buffer,
// so no host read of the refit roots sits between refit and tracing. The host built the topology;
// one workgroup refits bounds level by level, deepest first. Leaves transform their BLAS roots'
// eight corners, padded by a rounding bound so a leaf always contains the exact transformed box.
#extension GL_EXT_scalar_block_layout : require
#include "generated/shared.glsl"

layout(local_size_x = 64) in;

struct BvhNode {
    vec3 bmin;
    uint left_or_first;
    vec3 bmax;
    uint count;
};

// Mirrors `BvhInstance` in glsl/trace/compute.glsl.
struct BvhInstance {
    mat4 world_to_object;
    uint node_offset;
    uint prim_offset;
    uint mask;
    uint opaque;
    mat4 object_to_world;
};

layout(set = SET_ANIM, binding = TOP_FIT_NODES, scalar) buffer TlasNodes { BvhNode nodes[]; };
layout(set = SET_ANIM, binding = TOP_FIT_PRIMS, scalar) readonly buffer TlasPrims { uint prims[]; };
layout(set = SET_ANIM, binding = TOP_FIT_INSTANCES, scalar) readonly buffer Instances { BvhInstance instances[]; };
layout(set = SET_ANIM, binding = TOP_FIT_BLAS_NODES, scalar) readonly buffer BlasNodes { BvhNode blas_nodes[]; };
// Node indices deepest level first, then level_count + 1 boundaries at level_offset.
layout(set = SET_ANIM, binding = TOP_FIT_ORDER, scalar) readonly buffer Order { uint order[]; };

layout(push_constant) uniform Push {
    uint level_offset;
    uint level_count;
};

// Rounding bound of a transformed coordinate relative to its terms' magnitudes: gamma(4) = 2.4e-7,
// doubled to survive the rounding of the padded value itself.
const float PAD = 4.8e-7;

void grow_instance(uint inst, inout vec3 lo, inout vec3 hi) {
    BvhInstance bi = instances[inst];
    BvhNode root = blas_nodes[bi.node_offset];
    if (any(greaterThan(root.bmin, root.bmax))) return;  // empty tree
    mat4 m = bi.object_to_world;
    vec3 wlo = vec3(3.0e38), whi = vec3(-3.0e38);
    for (uint c = 0u; c < 8u; ++c) {
        vec3 p = vec3((c & 1u) == 0u ? root.bmin.x : root.bmax.x,
                      (c & 2u) == 0u ? root.bmin.y : root.bmax.y,
                      (c & 4u) == 0u ? root.bmin.z : root.bmax.z);
        vec3 w = (m * vec4(p, 1.0)).xyz;
        wlo = min(wlo, w);
        whi = max(whi, w);
    }
    vec3 a = max(abs(root.bmin), abs(root.bmax));
    vec3 mag = abs(m[0].xyz) * a.x + abs(m[1].xyz) * a.y + abs(m[2].xyz) * a.z + abs(m[3].xyz);
    wlo -= mag * PAD;
    whi += mag * PAD;
    // The host leaves non-finite instances out of the top level; one that became non-finite since cannot
    // be bounded.
    if (any(isinf(wlo)) || any(isnan(wlo)) || any(isinf(whi)) || any(isnan(whi))) return;
    lo = min(lo, wlo);
    hi = max(hi, whi);
}

void main() {
    for (uint l = 0u; l < level_count; ++l) {
        uint begin = order[level_offset + l], end = order[level_offset + l + 1u];
        for (uint i = begin + gl_LocalInvocationID.x; i < end; i += gl_WorkGroupSize.x) {
            uint n = order[i];
            BvhNode node = nodes[n];
            vec3 lo = vec3(3.0e38), hi = vec3(-3.0e38);
            if (node.count > 0u) {
                for (uint k = 0u; k < node.count; ++k) grow_instance(prims[node.left_or_first + k], lo, hi);
            } else {
                BvhNode a = nodes[node.left_or_first];
                BvhNode b = nodes[node.left_or_first + 1u];
                lo = min(a.bmin, b.bmin);
                hi = max(a.bmax, b.bmax);
            }
            nodes[n].bmin = lo;
            nodes[n].bmax = hi;
        }
        // The next level up reads what this one wrote.
        memoryBarrierBuffer();
        barrier();
    }
}
