#version 460
// Linear blend skinning into the ONE shared vertex buffer the rasterizer, AS builds and compute tracer
// read; same arithmetic as src/scene/skin.rs (the CPU reference). Also accumulates per-instance bounds
// for the BLAS rebuild policy.
#extension GL_EXT_scalar_block_layout : require
#include "../common/types.glsl"

layout(local_size_x = 64) in;

struct SkinVertex {
    vec3 position;
    vec3 normal;
    vec2 uv;
    vec4 tangent;
    uvec4 joints;
    vec4 weights;
};

layout(set = SET_ANIM, binding = SKIN_SOURCE, scalar) readonly buffer Source { SkinVertex src[]; };
layout(set = SET_ANIM, binding = SKIN_JOINTS, scalar) readonly buffer Joints { mat4 joints[]; };
layout(set = SET_ANIM, binding = SKIN_DEST, scalar) writeonly buffer Dest { Vertex dst[]; };
// Per skinned instance: min.xyz, max.xyz as order-preserving uints.
layout(set = SET_ANIM, binding = SKIN_BOUNDS, scalar) buffer Bounds { uint bounds[]; };

layout(push_constant, scalar) uniform Job {
    uint src_offset;
    uint dst_offset;
    uint vertex_count;
    uint joint_offset;
    uint slot;
} job;

// Monotonic float -> uint map, so atomicMin/Max order floats correctly.
uint orderable(float f) {
    uint u = floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= job.vertex_count) return;
    SkinVertex v = src[job.src_offset + i];
    mat4 m = mat4(0.0);
    for (int k = 0; k < 4; ++k) {
        if (v.weights[k] > 0.0) m += joints[job.joint_offset + v.joints[k]] * v.weights[k];
    }
    mat3 m3 = mat3(m);
    float det = determinant(m3);
    mat3 nm = abs(det) > 1.17549435e-38 ? transpose(inverse(m3)) : m3;
    vec3 n = nm * v.normal;
    n = dot(n, n) > 0.0 ? normalize(n) : v.normal;
    vec3 t = m3 * v.tangent.xyz;
    t = dot(t, t) > 0.0 ? normalize(t) : v.tangent.xyz;
    vec3 p = (m * vec4(v.position, 1.0)).xyz;

    Vertex o;
    o.position = p;
    o.normal = n;
    o.uv = v.uv;
    o.tangent = vec4(t, v.tangent.w);
    dst[job.dst_offset + i] = o;

    uint b = job.slot * 6u;
    for (int k = 0; k < 3; ++k) {
        atomicMin(bounds[b + k], orderable(p[k]));
        atomicMax(bounds[b + 3 + k], orderable(p[k]));
    }
}
