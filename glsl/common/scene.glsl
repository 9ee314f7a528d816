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
// Diffuse PRT transfer (layout: shared_values.rs SCENE_PRT; prt.glsl).
layout(set = SET_SCENE, binding = SCENE_PRT, scalar) readonly buffer PrtData { uint prt_data[]; };
layout(set = SET_SCENE, binding = SCENE_TEXTURES) uniform sampler2D textures[];  // bindless: last binding
// Ray counters for benchmarks (by kind only when COUNT_RAYS is on; the
// truncated and bad-pixel slots always):
// by RAY_KIND_*: camera rays (pure RT), shadow rays, reflection/refraction rays.
layout(set = SET_SCENE, binding = SCENE_RAY_COUNTERS) buffer RayCounters { uint ray_counts[RAY_COUNTER_SLOTS]; };
// The ray-tracing budget (render/budget): statistics the `heuristic` pass
// gathers, and the host's selection of the objects whose pixels get
// ray-traced effects.
layout(set = SET_SCENE, binding = SCENE_BUDGET_STATS) buffer BudgetStats { uint budget_stats[]; };
layout(set = SET_SCENE, binding = SCENE_BUDGET_MASK) readonly buffer BudgetMask { uint budget_mask[]; };

// A 32-bit integer hash (Jarzynski & Olano 2020's PCG hash): uniform bits
// for the budget's partial effects (from a pixel tile's index) and the
// reference pass's random numbers.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The ray-traced effects (EFFECT_* bits) pixel `px` of `instance` gets: all
// without a budget, else those the budget selected for its object, plus
// its partial effects where px's tile falls within their share. The hash
// ignores the share, so a larger share keeps every tile a smaller one had.
uint budget_effects(uint instance, ivec2 px) {
    if ((frame.flags & FRAME_BUDGET) == 0u) return EFFECT_ALL;
    uint word = budget_mask[instances[instance].object_id];
    uint bits = word & EFFECT_ALL;
    uint partial = (word >> EFFECT_PARTIAL_SHIFT) & EFFECT_ALL;
    if (partial != 0u) {
        uvec2 tile = uvec2(px) / BUDGET_TILE;
        uint h = pcg_hash(tile.x ^ pcg_hash(tile.y)) & 0xFFFFu;
        if (h < (word >> EFFECT_FRACTION_SHIFT)) bits |= partial;
    }
    return bits;
}

vec4 sample_tex(int index, vec2 uv, vec4 fallback) {
    return index < 0 ? fallback : texture(textures[nonuniformEXT(index)], uv);
}

// Texture level of detail at ray hits (ray cones, Akenine-Möller et al.,
// "Texture Level of Detail Strategies for Real-Time Ray Tracing", Ray
// Tracing Gems ch. 20): the mip level is g_hit_lod, set per hit from the
// cone's footprint and the triangle's texel density, plus log2 of the
// texture's size. Rays have no screen-space derivatives; without this every
// secondary hit samples mip 0 and textures seen in mirrors, through glass
// or by pure-RT camera rays sparkle.
float g_hit_lod = 0.0;
// Pure-RT camera rays sample with the same screen-space uv gradients the
// rasterizer derives (see primary.glsl), so both modes pick the same texels.
bool g_hit_grad = false;
vec2 g_uv_dx = vec2(0.0);
vec2 g_uv_dy = vec2(0.0);

vec4 sample_tex_cone(int index, vec2 uv, vec4 fallback) {
    if (index < 0) return fallback;
    if (g_hit_grad) return textureGrad(textures[nonuniformEXT(index)], uv, g_uv_dx, g_uv_dy);
    vec2 size = vec2(textureSize(textures[nonuniformEXT(index)], 0));
    return textureLod(textures[nonuniformEXT(index)], uv, g_hit_lod + 0.5 * log2(size.x * size.y));
}

vec4 sample_tex_lod(int index, vec2 uv, float lod, vec4 fallback) {
    return index < 0 ? fallback : textureLod(textures[nonuniformEXT(index)], uv, lod);
}

#endif
