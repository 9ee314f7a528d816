// Set 0: the scene, bound by every pass. One copy of the geometry.
#ifndef SCENE_GLSL
#define SCENE_GLSL
#include "types.glsl"

layout(set = 0, binding = 0, scalar) uniform FrameBlock { Frame frame; };
layout(set = 0, binding = 1, scalar) readonly buffer Vertices { Vertex vertices[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Indices { uint indices[]; };
layout(set = 0, binding = 3, scalar) readonly buffer Materials { Material materials[]; };
layout(set = 0, binding = 4, scalar) readonly buffer Instances { Instance instances[]; };
layout(set = 0, binding = 5, scalar) readonly buffer Lights { Light lights[]; };
layout(set = 0, binding = 6) uniform sampler2D env_map;
layout(set = 0, binding = 8) uniform sampler2D textures[];  // bindless: last binding
// Ray counters for benchmarks (written only when COUNT_RAYS is on):
// [0] camera rays (pure RT), [1] shadow rays, [2] reflection/refraction rays.
layout(set = 0, binding = 7) buffer RayCounters { uint ray_counts[4]; };

vec4 sample_tex(int index, vec2 uv, vec4 fallback) {
    return index < 0 ? fallback : texture(textures[nonuniformEXT(index)], uv);
}

vec4 sample_tex_lod(int index, vec2 uv, float lod, vec4 fallback) {
    return index < 0 ? fallback : textureLod(textures[nonuniformEXT(index)], uv, lod);
}

#endif
