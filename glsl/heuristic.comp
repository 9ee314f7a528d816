#version 460
// Pass `heuristic`: per-object covered pixels and bounds for the budget (render/budget), by atomics
// over the hit ids. No per-object draw or occlusion query: the G-buffer already says who is visible.
//
// Why reduced before the global atomics: five of them per pixel on a handful of objects contend (the
// pass took 7 % of the default scene's frame on lavapipe, 12 % at 320x180). Lanes that see the same
// object combine their pixels first: per subgroup where the device has subgroup arithmetic (the
// default), else (HEURISTIC_SHARED) per 8x8 tile in shared memory. Measured in
// bench/results/heuristic-reduction.md.
#ifndef HEURISTIC_SHARED
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#endif
#include "common/scene.glsl"

// No primary hit (object ids are indices, far below it).
#define NO_OBJECT 0xffffffffu

layout(set = SET_PASS, binding = GB_HIT) uniform usampler2D gb_hit;

void add_stats(uint object, uint pixels, uvec2 lo, uvec2 hi) {
    uint base = BUDGET_STAT_WORDS * object;
    atomicAdd(budget_stats[base], pixels);
    atomicMin(budget_stats[base + 1u], lo.x);
    atomicMin(budget_stats[base + 2u], lo.y);
    atomicMax(budget_stats[base + 3u], hi.x);
    atomicMax(budget_stats[base + 4u], hi.y);
}

uint hit_at(uvec2 px) {
    return all(lessThan(px, frame.resolution)) ? texelFetch(gb_hit, ivec2(px), 0).x : 0u;
}

uint object_of(uint hit) {
    return hit == 0u ? NO_OBJECT : instances[hit - 1u].object_id;
}

#ifndef HEURISTIC_SHARED

// Each invocation takes a block of HEURISTIC_BLOCK_W x HEURISTIC_BLOCK_H pixels: on a CPU device the
// pass's floor was one invocation, one object-id read and one subgroup round per pixel, 4 % of a
// small scene's frame; a block's pixels usually share an instance and reduce in registers.
#define BLOCK_W uint(HEURISTIC_BLOCK_W)
#define BLOCK_H uint(HEURISTIC_BLOCK_H)
#define BLOCK_PIXELS (BLOCK_W * BLOCK_H)
// The pass dispatches a workgroup per 8 x 8 blocks (render/passes/heuristic.rs).
layout(local_size_x = 8, local_size_y = 8) in;

uvec2 in_block(uint i) { return uvec2(i % BLOCK_W, i / BLOCK_W); }

void main() {
    uvec2 origin = uvec2(BLOCK_W, BLOCK_H) * gl_GlobalInvocationID.xy;
    uint objects[BLOCK_PIXELS];
    uint remaining = 0u, previous_hit = 0u, previous_object = NO_OBJECT;
    for (uint i = 0u; i < BLOCK_PIXELS; ++i) {
        uint hit = hit_at(origin + in_block(i));
        // Neighbours on one instance read its object id once.
        if (hit != previous_hit) previous_object = object_of(hit);
        previous_hit = hit;
        objects[i] = previous_object;
        if (previous_object != NO_OBJECT) remaining |= 1u << i;
    }
    // One round per distinct object in the block, and within it one per distinct object among the
    // active lanes (usually one): its lanes reduce together and one adds the sum.
    while (remaining != 0u) {
        uint object = objects[findLSB(remaining)];
        uint pixels = 0u;
        uvec2 lo = uvec2(0xffffffffu), hi = uvec2(0u);
        for (uint i = 0u; i < BLOCK_PIXELS; ++i) {
            if ((remaining & (1u << i)) != 0u && objects[i] == object) {
                pixels += 1u;
                lo = min(lo, origin + in_block(i));
                hi = max(hi, origin + in_block(i));
                remaining &= ~(1u << i);
            }
        }
        for (;;) {
            if (object == subgroupBroadcastFirst(object)) {
                uint sum = subgroupAdd(pixels);
                uvec2 l = subgroupMin(lo), h = subgroupMax(hi);
                if (subgroupElect()) add_stats(object, sum, l, h);
                break;
            }
        }
    }
}

#else

layout(local_size_x = 8, local_size_y = 8) in;

#define TILE_PIXELS 64u

// A tile's objects in the order its pixels claimed them: at most 64 distinct, so every pixel finds its
// object's slot or a free one. The scan starts at slot 0: a tile sees a few objects, and every pixel
// after the first object's walks the claim loop (a hash start would skip it for most scenes' ids).
shared uint s_object[TILE_PIXELS];
shared uint s_pixels[TILE_PIXELS];
shared uvec2 s_min[TILE_PIXELS];
shared uvec2 s_max[TILE_PIXELS];

void main() {
    uint lid = gl_LocalInvocationIndex;
    s_object[lid] = NO_OBJECT;
    s_pixels[lid] = 0u;
    s_min[lid] = uvec2(0xffffffffu);
    s_max[lid] = uvec2(0u);
    barrier();
    uvec2 px = gl_GlobalInvocationID.xy;
    uint object = object_of(hit_at(px));
    if (object != NO_OBJECT) {
        uint slot = 0u;
        for (uint probe = 0u; probe < TILE_PIXELS; ++probe) {
            uint was = atomicCompSwap(s_object[slot], NO_OBJECT, object);
            if (was == NO_OBJECT || was == object) break;
            slot = (slot + 1u) % TILE_PIXELS;
        }
        atomicAdd(s_pixels[slot], 1u);
        atomicMin(s_min[slot].x, px.x);
        atomicMin(s_min[slot].y, px.y);
        atomicMax(s_max[slot].x, px.x);
        atomicMax(s_max[slot].y, px.y);
    }
    barrier();
    if (s_object[lid] != NO_OBJECT) add_stats(s_object[lid], s_pixels[lid], s_min[lid], s_max[lid]);
}

#endif
