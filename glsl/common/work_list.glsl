// Compacted work list (render/passes/compacted.rs): a select kernel lists the pixels needing a pass's
// expensive kernel, which then runs one invocation per entry, dispatched indirectly. Why: in a
// full-screen launch, lanes of a SIMD vector (llvmpipe) or warp whose pixels have nothing to do idle
// while neighbours trace. Appends follow invocation order, so neighbouring entries are mostly
// neighbouring pixels. The header (reset by the host each frame) is both a VkDispatchIndirectCommand
// (WORK_GROUPS_X groups of WORK_GROUP_SIZE) and, at WORK_COUNT, a VkTraceRaysIndirectCommandKHR.
// The list is an r32ui image read linearly: entry i at (i % width, i / width), pixel x | y << 16.
#ifndef WORK_LIST_GLSL
#define WORK_LIST_GLSL

layout(set = SET_PASS, binding = WORK_HEADER) coherent buffer WorkHeader { uint work[WORK_HEADER_WORDS]; };
layout(set = SET_PASS, binding = WORK_LIST, r32ui) uniform uimage2D work_list;

ivec2 work_slot(uint i) {
    uint w = uint(imageSize(work_list).x);
    return ivec2(i % w, i / w);
}

void work_append(ivec2 px) {
    uint i = atomicAdd(work[WORK_COUNT], 1u);
    // Entries are numbered without gaps, so each workgroup's first entry counts one workgroup.
    if (i % WORK_GROUP_SIZE == 0u) atomicAdd(work[WORK_GROUPS_X], 1u);
    imageStore(work_list, work_slot(i), uvec4(uint(px.x) | (uint(px.y) << 16u)));
}

// False past the end (the last group's spare invocations, or a full-frame launch where the device
// has no indirect ray-tracing launch).
bool work_item(uint i, out ivec2 px) {
    px = ivec2(0);
    if (i >= work[WORK_COUNT]) return false;
    uint v = imageLoad(work_list, work_slot(i)).x;
    px = ivec2(v & 0xffffu, v >> 16u);
    return true;
}

#endif
