#version 460
// Refit of skinned meshes' per-instance BVHs (compute backend): one workgroup per BVH, levels deepest
// first. Leaves take their skinned triangles' exact min/max, as the CPU build does, so a refit tree
// equals a CPU refit bit for bit. The root also lands in `roots` for the host (rebuild policy,
// next top-level topology).
#extension GL_EXT_scalar_block_layout : require
#include "../common/types.glsl"

layout(local_size_x = 64) in;

struct BvhNode {
    vec3 bmin;
    uint left_or_first;
    vec3 bmax;
    uint count;
};

struct RefitJob {
    uint node_offset;    // this BVH's root in `nodes`
    uint prim_offset;    // its triangle order in `prims`
    uint first_index;    // its triangles in the shared index buffer
    uint vertex_offset;  // its skinned vertices in the shared vertex buffer
    uint order_offset;   // its nodes, deepest level first, in `order`
    uint level_offset;   // level_count + 1 boundaries into its `order` range
    uint level_count;
    uint pad;
};

layout(set = SET_ANIM, binding = REFIT_NODES, scalar) buffer Nodes { BvhNode nodes[]; };
layout(set = SET_ANIM, binding = REFIT_PRIMS, scalar) readonly buffer Prims { uint prims[]; };
layout(set = SET_ANIM, binding = REFIT_VERTICES, scalar) readonly buffer Vertices { Vertex vertices[]; };
layout(set = SET_ANIM, binding = REFIT_INDICES, scalar) readonly buffer Indices { uint indices[]; };
layout(set = SET_ANIM, binding = REFIT_JOBS, scalar) readonly buffer Jobs { RefitJob jobs[]; };
layout(set = SET_ANIM, binding = REFIT_ORDER, scalar) readonly buffer Order { uint order[]; };
layout(set = SET_ANIM, binding = REFIT_ROOTS, scalar) writeonly buffer Roots { BvhNode roots[]; };

vec3 position(RefitJob job, uint tri, uint corner) {
    return vertices[job.vertex_offset + indices[job.first_index + 3u * tri + corner]].position;
}

void main() {
    RefitJob job = jobs[gl_WorkGroupID.x];
    for (uint l = 0u; l < job.level_count; ++l) {
        uint begin = order[job.level_offset + l], end = order[job.level_offset + l + 1u];
        for (uint i = begin + gl_LocalInvocationID.x; i < end; i += gl_WorkGroupSize.x) {
            uint n = job.node_offset + order[job.order_offset + i];
            BvhNode node = nodes[n];
            vec3 lo = vec3(3.0e38), hi = vec3(-3.0e38);
            if (node.count > 0u) {
                for (uint k = 0u; k < node.count; ++k) {
                    uint tri = prims[job.prim_offset + node.left_or_first + k];
                    for (uint c = 0u; c < 3u; ++c) {
                        vec3 p = position(job, tri, c);
                        lo = min(lo, p);
                        hi = max(hi, p);
                    }
                }
            } else {
                BvhNode a = nodes[job.node_offset + node.left_or_first];
                BvhNode b = nodes[job.node_offset + node.left_or_first + 1u];
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
    if (gl_LocalInvocationID.x == 0u) roots[gl_WorkGroupID.x] = nodes[job.node_offset];
}
