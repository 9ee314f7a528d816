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

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = GB_HIT) uniform usampler2D gb_hit;

void add_stats(uint object, uint pixels, uvec2 lo, uvec2 hi) {
    uint base = BUDGET_STAT_WORDS * object;
    atomicAdd(budget_stats[base], pixels);
    atomicMin(budget_stats[base + 1u], lo.x);
    atomicMin(budget_stats[base + 2u], lo.y);
    atomicMax(budget_stats[base + 3u], hi.x);
    atomicMax(budget_stats[base + 4u], hi.y);
}

uint object_at(uvec2 px) {
    uint hit = all(lessThan(px, frame.resolution)) ? texelFetch(gb_hit, ivec2(px), 0).x : 0u;
    return hit == 0u ? NO_OBJECT : instances[hit - 1u].object_id;
}

#ifndef HEURISTIC_SHARED

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    uint object = object_at(px);
    if (object == NO_OBJECT) return;
    // One round per distinct object among the active lanes (usually one): its lanes reduce together.
    for (;;) {
        if (object == subgroupBroadcastFirst(object)) {
            uint pixels = subgroupAdd(1u);
            uvec2 lo = subgroupMin(px), hi = subgroupMax(px);
            if (subgroupElect()) add_stats(object, pixels, lo, hi);
            break;
        }
    }
}

#else

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
    uint object = object_at(px);
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
