#version 460
// Two-phase occlusion culling of G-buffer clusters (render/occlusion.rs), one invocation per cluster.
// Phase 1 draws last frame's visible clusters in the frustum; phase 2 tests the rest against the
// pyramid built from phase 1's depth and records visibility for next frame. Conservative: a cluster
// is culled only when none of its triangles can cover a pixel centre in front of what is drawn.
#include "common/scene.glsl"
#include "common/cluster.glsl"
layout(local_size_x = 64) in;

layout(set = SET_PASS, binding = OCC_VISIBLE) buffer Visible { uint visible[]; };
layout(set = SET_PASS, binding = OCC_COMMANDS, scalar) buffer Commands { DrawCommand commands[]; };
layout(set = SET_PASS, binding = OCC_COUNTERS) buffer Counters { uint counters[OCC_COUNTER_SLOTS]; };
layout(set = SET_PASS, binding = OCC_HIZ) uniform sampler2D hiz;

layout(push_constant) uniform Push {
    uint phase;  // 1 or 2
    uint count;  // clusters
    uint levels;  // pyramid levels (level k: 2^(k+1) pixels a texel)
    uint width;  // depth buffer size
    uint height;
} pc;

// Finer than 2x2 texels, so a box is not kept only because a coarse texel also covers the sky beside it.
const int TEXELS = 8;

// `p0..p1` inclusive pixels.
bool occluded(ivec2 p0, ivec2 p1, float z_near) {
    int k = 0;
    while (k < int(pc.levels) && any(greaterThanEqual((p1 >> (k + 1)) - (p0 >> (k + 1)), ivec2(TEXELS)))) k++;
    if (k >= int(pc.levels)) return false;
    ivec2 t0 = p0 >> (k + 1), t1 = p1 >> (k + 1);
    // Margin for the rounding of the raster's transform.
    float z = z_near * 1.0001 + 1e-7;
    for (int y = t0.y; y <= t1.y; y++) {
        for (int x = t0.x; x <= t1.x; x++) {
            if (texelFetch(hiz, ivec2(x, y), k).r <= z) return false;
        }
    }
    return true;
}

void main() {
    uint c = gl_GlobalInvocationID.x;
    if (c >= pc.count) return;
    if (pc.phase == 1u && c == 0u) {
        for (uint i = 0u; i < OCC_COUNTER_SLOTS; i++) counters[i] = 0u;
    }
    Cluster cl = clusters[c];
    if (cl.lo.x > cl.hi.x) {
        // No bounds (a skinned draw, gpu/clusters.rs): always drawn, in phase 1.
        if (pc.phase == 1u) {
            commands[c].instance_count = 1u;
        } else {
            visible[c] = 1u;
            commands[pc.count + c].instance_count = 0u;
            atomicAdd(counters[0], 1u);
            atomicAdd(counters[4], commands[c].vertex_count / 3u);
        }
        return;
    }
    mat4 m = frame.view_proj * instances[cl.instance].world;
    // Outcodes: clip planes are linear in homogeneous space, so this holds for corners behind the camera
    // too. Far plane at infinity.
    uint all_out = 31u;
    bool behind = false;
    vec3 lo = vec3(1e30), hi = vec3(-1e30);
    for (uint i = 0u; i < 8u; i++) {
        vec3 corner = vec3((i & 1u) != 0u ? cl.hi.x : cl.lo.x, (i & 2u) != 0u ? cl.hi.y : cl.lo.y,
                           (i & 4u) != 0u ? cl.hi.z : cl.lo.z);
        vec4 p = m * vec4(corner, 1.0);
        uint o = (p.x < -p.w ? 1u : 0u) | (p.x > p.w ? 2u : 0u) | (p.y < -p.w ? 4u : 0u) |
                 (p.y > p.w ? 8u : 0u) | (p.z > p.w ? 16u : 0u);
        all_out &= o;
        if (p.w <= 1e-6) {
            behind = true;
        } else {
            vec3 ndc = p.xyz / p.w;
            lo = min(lo, ndc);
            hi = max(hi, ndc);
        }
    }
    bool in_frustum = all_out == 0u;
    bool drawn_first = visible[c] != 0u && in_frustum;
    if (pc.phase == 1u) {
        commands[c].instance_count = drawn_first ? 1u : 0u;
        return;
    }
    bool vis = in_frustum;
    // A box reaching behind the camera covers unbounded screen space: kept.
    if (vis && !behind) {
        vec2 size = vec2(pc.width, pc.height);
        // One pixel margin each side.
        ivec2 last = ivec2(pc.width, pc.height) - 1;
        ivec2 p0 = clamp(ivec2(floor((lo.xy * 0.5 + 0.5) * size)) - 1, ivec2(0), last);
        ivec2 p1 = clamp(ivec2(floor((hi.xy * 0.5 + 0.5) * size)) + 1, ivec2(0), last);
        vis = !occluded(p0, p1, hi.z);
    }
    visible[c] = vis ? 1u : 0u;
    commands[pc.count + c].instance_count = (vis && !drawn_first) ? 1u : 0u;
    uint slot = !in_frustum ? 3u : drawn_first ? 0u : vis ? 1u : 2u;
    atomicAdd(counters[slot], 1u);
    if (slot <= 1u) atomicAdd(counters[4], commands[c].vertex_count / 3u);
}
