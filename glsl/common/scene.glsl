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
layout(set = SET_SCENE, binding = SCENE_TEXTURES) uniform sampler2D textures[];  // bindless: last binding
// Ray counters for benchmarks (written only when COUNT_RAYS is on):
// by RAY_KIND_*: camera rays (pure RT), shadow rays, reflection/refraction rays.
layout(set = SET_SCENE, binding = SCENE_RAY_COUNTERS) buffer RayCounters { uint ray_counts[4]; };

vec4 sample_tex(int index, vec2 uv, vec4 fallback) {
    return index < 0 ? fallback : texture(textures[nonuniformEXT(index)], uv);
}

vec4 sample_tex_lod(int index, vec2 uv, float lod, vec4 fallback) {
    return index < 0 ? fallback : textureLod(textures[nonuniformEXT(index)], uv, lod);
}

#endif
