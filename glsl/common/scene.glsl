// Set 0: the scene, bound by every pass. One copy of the geometry.
#ifndef SCENE_GLSL
#define SCENE_GLSL
#include "types.glsl"

layout(set = SET_SCENE, binding = SCENE_FRAME, scalar) uniform FrameBlock { Frame frame; };
layout(set = SET_SCENE, binding = SCENE_VERTICES, scalar) readonly buffer Vertices { Vertex vertices[]; };
layout(set = SET_SCENE, binding = SCENE_INDICES, scalar) readonly buffer Indices { uint indices[]; };
layout(set = SET_SCENE, binding = SCENE_MATERIALS, scalar) readonly buffer Materials { Material materials[]; };
layout(set = SET_SCENE, binding = SCENE_INSTANCES, scalar) readonly buffer Instances { Instance instances[]; };
layout(set = SET_SCENE, binding = SCENE_LIGHTS, scalar) readonly buffer Lights { Light lights[]; };
layout(set = SET_SCENE, binding = SCENE_ENV_MAP) uniform sampler2D env_map;
// The map prefiltered by GGX (mip k: roughness k / (ENV_SPECULAR_LEVELS - 1)) and the split-sum table.
layout(set = SET_SCENE, binding = SCENE_ENV_SPECULAR) uniform sampler2D env_specular_map;
layout(set = SET_SCENE, binding = SCENE_DFG) uniform sampler2D dfg_table;
// Diffuse PRT transfer (layout: shared_values.rs SCENE_PRT; prt.glsl).
layout(set = SET_SCENE, binding = SCENE_PRT, scalar) readonly buffer PrtData { uint prt_data[]; };
layout(set = SET_SCENE, binding = SCENE_TEXTURES) uniform sampler2D textures[];  // bindless: last binding
// Benchmark counters by RAY_KIND_* (only with FRAME_COUNT_RAYS); the truncated and bad-pixel slots always.
layout(set = SET_SCENE, binding = SCENE_RAY_COUNTERS) buffer RayCounters { uint ray_counts[RAY_COUNTER_SLOTS]; };
// render/budget: statistics `heuristic` gathers, and the host's per-object selection.
layout(set = SET_SCENE, binding = SCENE_BUDGET_STATS) buffer BudgetStats { uint budget_stats[]; };
layout(set = SET_SCENE, binding = SCENE_BUDGET_MASK) readonly buffer BudgetMask { uint budget_mask[]; };

// PCG hash (Jarzynski & Olano 2020): reference random numbers and per-pixel filter rotations.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// px's rank in the 8x8 Bayer matrix (BUDGET_LATTICE = 8): the bit-reversed interleave of (x ^ y, y).
// Ranks below 4^k are the multiples of 8 / 2^k: an even lattice for every share.
uint budget_rank(ivec2 px) {
    uint y = uint(px.y) & 7u, xy = (uint(px.x) ^ uint(px.y)) & 7u;
    return ((xy & 1u) << 5) | ((y & 1u) << 4) | ((xy & 2u) << 2) | ((y & 2u) << 1) | ((xy & 4u) >> 1)
        | ((y & 4u) >> 2);
}

// The partial effects of `word` traced at px.
uint budget_partial_here(uint word, ivec2 px) {
    return budget_rank(px) < (word >> EFFECT_FRACTION_SHIFT) ? (word >> EFFECT_PARTIAL_SHIFT) & EFFECT_ALL : 0u;
}

// All effects without a budget; else the object's selection plus its partial effects where px's rank
// falls within their share. Pixel-scale: only the compacted specular chains get a share (the host never
// gives one to shadows, whose `direct` pass would diverge per pixel).
uint budget_effects(uint instance, ivec2 px) {
    if ((frame.flags & FRAME_BUDGET) == 0u) return EFFECT_ALL;
    uint word = budget_mask[instances[instance].object_id];
    return (word & EFFECT_ALL) | budget_partial_here(word, px);
}

// KHR_texture_transform: a reference's uv, and uv differences (gradients) under its linear part.
vec2 uv_apply(UvTransform t, vec2 uv) {
    return vec2(dot(t.row0, vec3(uv, 1.0)), dot(t.row1, vec3(uv, 1.0)));
}

vec2 uv_apply_linear(UvTransform t, vec2 d) {
    return vec2(dot(t.row0.xy, d), dot(t.row1.xy, d));
}

// The mip shift of a footprint mapped through `t`: half the log2 of the area it scales by.
float uv_lod_shift(UvTransform t) {
    return 0.5 * log2(max(abs(t.row0.x * t.row1.y - t.row0.y * t.row1.x), 1e-30));
}

vec4 sample_tex(int index, UvTransform xf, vec2 uv, vec4 fallback) {
    return index < 0 ? fallback : texture(textures[nonuniformEXT(index)], uv_apply(xf, uv));
}

vec4 sample_tex_grad(int index, UvTransform xf, vec2 uv, vec2 dx, vec2 dy, vec4 fallback) {
    if (index < 0) return fallback;
    return textureGrad(textures[nonuniformEXT(index)], uv_apply(xf, uv), uv_apply_linear(xf, dx),
                       uv_apply_linear(xf, dy));
}

// Ray cones (Akenine-Möller et al., Ray Tracing Gems ch. 20): rays have no screen derivatives, so
// g_hit_lod (cone footprint and texel density, per hit) plus log2 texture size picks the mip; without
// it secondary hits sample mip 0 and textures in mirrors, through glass or by RT camera rays sparkle.
float g_hit_lod = 0.0;
// Pure-RT camera rays use the rasterizer's uv gradients (primary.glsl) so both modes pick the same texels.
bool g_hit_grad = false;
vec2 g_uv_dx = vec2(0.0);
vec2 g_uv_dy = vec2(0.0);

// The level a footprint of log2 uv-area `lod` (g_hit_lod's units) covers on texture `index` under `xf`.
float texel_lod(int index, UvTransform xf, float lod) {
    vec2 size = vec2(textureSize(textures[nonuniformEXT(index)], 0));
    return lod + uv_lod_shift(xf) + 0.5 * log2(size.x * size.y);
}

vec4 sample_tex_cone(int index, UvTransform xf, vec2 uv, vec4 fallback) {
    if (index < 0) return fallback;
    if (g_hit_grad) return sample_tex_grad(index, xf, uv, g_uv_dx, g_uv_dy, fallback);
    return textureLod(textures[nonuniformEXT(index)], uv_apply(xf, uv), texel_lod(index, xf, g_hit_lod));
}

// An explicit texel-space level (0: the finest).
vec4 sample_tex_lod(int index, UvTransform xf, vec2 uv, float lod, vec4 fallback) {
    return index < 0 ? fallback : textureLod(textures[nonuniformEXT(index)], uv_apply(xf, uv), lod);
}

#endif
