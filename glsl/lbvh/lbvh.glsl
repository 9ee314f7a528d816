// The device-side LBVH builder's resources (accel/lbvh.rs): Karras 2012 over 30-bit Morton codes of
// the triangle centroids, radix-sorted. One set; the host binds a second with the key/value pairs
// swapped so each sort pass reads what the last one wrote.
#ifndef LBVH_GLSL
#define LBVH_GLSL

#extension GL_EXT_scalar_block_layout : require
#include "generated/shared.glsl"

layout(local_size_x = LBVH_GROUP) in;

layout(push_constant, scalar) uniform Push {
    uint count;   // triangles (leaves)
    uint shift;   // the sort pass's first key bit
    uint blocks;  // radix blocks: ceil(count / LBVH_RADIX_BLOCK)
    uint pad;
    vec3 lo;      // centroid bounds' low corner
    float pad1;
    vec3 scale;   // 1024 / centroid extent per axis (0 for a flat axis)
    float pad2;
} pc;

layout(set = SET_LBVH, binding = LBVH_TRIANGLES, scalar) readonly buffer Triangles { float tris[]; };
layout(set = SET_LBVH, binding = LBVH_KEYS, std430) buffer Keys { uint keys[]; };
layout(set = SET_LBVH, binding = LBVH_VALUES, std430) buffer Values { uint values[]; };
layout(set = SET_LBVH, binding = LBVH_KEYS_OUT, std430) buffer KeysOut { uint keys_out[]; };
layout(set = SET_LBVH, binding = LBVH_VALUES_OUT, std430) buffer ValuesOut { uint values_out[]; };
layout(set = SET_LBVH, binding = LBVH_HISTOGRAM, std430) buffer Histogram { uint hist[]; };
layout(set = SET_LBVH, binding = LBVH_CHILDREN, std430) buffer Children { uvec2 children[]; };
layout(set = SET_LBVH, binding = LBVH_PARENTS, std430) buffer Parents { uint parents[]; };
layout(set = SET_LBVH, binding = LBVH_BOXES, scalar) coherent buffer Boxes { float boxes[]; };
layout(set = SET_LBVH, binding = LBVH_FLAGS, std430) coherent buffer Flags { uint flags[]; };

const uint RADIX = 1u << LBVH_RADIX_BITS;
const uint NO_PARENT = 0xFFFFFFFFu;

vec3 corner(uint tri, uint k) {
    uint at = 9u * tri + 3u * k;
    return vec3(tris[at], tris[at + 1u], tris[at + 2u]);
}

#endif
