// A compacted work list (render/passes/compacted.rs): a select kernel lists
// the pixels that need a pass's expensive kernel, which then runs one
// invocation per entry, dispatched indirectly. Why: in a full-screen
// launch the lanes of a SIMD vector (llvmpipe) or warp (GPU) whose pixels
// have nothing to do idle while their neighbours trace; listed, every lane
// has a pixel. Appends are in the select kernel's invocation order (one
// atomic per pixel, aggregated per subgroup by the hardware or llvmpipe's
// lane loop), so neighbouring list entries are mostly neighbouring pixels.
//
// The header (WORK_HEADER_WORDS words, reset by the host each frame) is both
// indirect commands: a VkDispatchIndirectCommand (WORK_GROUPS_X workgroups
// of WORK_GROUP_SIZE, then 1, 1) and, at WORK_COUNT, a
// VkTraceRaysIndirectCommandKHR (width = the count, then 1, 1). The list is
// an r32ui image of the frame's size read as a linear array: entry i at
// (i % width, i / width), a pixel packed as x | y << 16.
#ifndef WORK_LIST_GLSL
#define WORK_LIST_GLSL

layout(set = SET_PASS, binding = WORK_HEADER) coherent buffer WorkHeader { uint work[WORK_HEADER_WORDS]; };
layout(set = SET_PASS, binding = WORK_LIST, r32ui) uniform uimage2D work_list;

ivec2 work_slot(uint i) {
    uint w = uint(imageSize(work_list).x);
    return ivec2(i % w, i / w);
}

// Lists `px` (select kernel).
void work_append(ivec2 px) {
    uint i = atomicAdd(work[WORK_COUNT], 1u);
    // Entries are numbered without gaps, so the first entry of each
    // workgroup counts one workgroup.
    if (i % WORK_GROUP_SIZE == 0u) atomicAdd(work[WORK_GROUPS_X], 1u);
    imageStore(work_list, work_slot(i), uvec4(uint(px.x) | (uint(px.y) << 16u)));
}

// The pixel of entry `i` (the listed kernel); false past the end (the last
// workgroup's spare invocations, or a full-frame launch where the device
// has no indirect ray-tracing launch).
bool work_item(uint i, out ivec2 px) {
    px = ivec2(0);
    if (i >= work[WORK_COUNT]) return false;
    uint v = imageLoad(work_list, work_slot(i)).x;
    px = ivec2(v & 0xffffu, v >> 16u);
    return true;
}

#endif
