#version 460
// Pass `heuristic`: per-object covered pixels and bounds for the budget (render/budget), by atomics
// over the hit ids. No per-object draw or occlusion query: the G-buffer already says who is visible.
#include "common/scene.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = GB_HIT) uniform usampler2D gb_hit;

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(px, frame.resolution))) return;
    uint hit = texelFetch(gb_hit, ivec2(px), 0).x;
    if (hit == 0u) return;
    uint base = BUDGET_STAT_WORDS * instances[hit - 1u].object_id;
    atomicAdd(budget_stats[base], 1u);
    atomicMin(budget_stats[base + 1u], px.x);
    atomicMin(budget_stats[base + 2u], px.y);
    atomicMax(budget_stats[base + 3u], px.x);
    atomicMax(budget_stats[base + 4u], px.y);
}
