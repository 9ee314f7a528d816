// The budget's raster shadow fallback (gpu/shadow_map.rs): a depth layer per directional or spot
// light, PCF-filtered where a pixel's shadow bit is off. Point lights have none: unshadowed.
#ifndef SHADOW_MAP_GLSL
#define SHADOW_MAP_GLSL
#include "scene.glsl"

struct ShadowView {
    mat4 view_proj;   // depth 0 near .. 1 far
    float texel;      // world size of a texel (at unit distance if perspective)
    float perspective;
    float pad0;
    float pad1;
};

layout(set = SET_SCENE, binding = SCENE_SHADOW_MAPS) uniform sampler2DArrayShadow shadow_maps;
layout(set = SET_SCENE, binding = SCENE_SHADOW_VIEWS, scalar) readonly buffer ShadowViews { ShadowView shadow_views[]; };

// `n`: unit geometric normal on the light's side; `dist`: distance to a spot light. Against acne at
// any slope the receiver moves SHADOW_NORMAL_OFFSET texels along n (texels grow with distance under a
// perspective map) and the pass uses slope-scaled depth bias (render/passes/shadow_map.rs); contact
// shadows start a texel or two late.
float shadow_map_visibility(uint light, vec3 p, vec3 n, float dist) {
    ShadowView sv = shadow_views[light];
    float texel = sv.texel * (sv.perspective > 0.5 ? dist : 1.0);
    vec4 c = sv.view_proj * vec4(p + n * (SHADOW_NORMAL_OFFSET * texel), 1.0);
    if (c.w <= 0.0) return 1.0;
    vec3 ndc = c.xyz / c.w;
    // Outside the map nothing was rasterized: lit.
    if (any(greaterThan(abs(ndc.xy), vec2(1.0))) || ndc.z > 1.0 || ndc.z < 0.0) return 1.0;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    vec2 step = 1.0 / vec2(textureSize(shadow_maps, 0).xy);
    // 3x3 taps of the comparison sampler's bilinear 2x2: a 4x4-texel PCF.
    float sum = 0.0;
    for (int y = -1; y <= 1; ++y) {
        for (int x = -1; x <= 1; ++x) {
            sum += texture(shadow_maps, vec4(uv + vec2(x, y) * step, float(light), ndc.z));
        }
    }
    return sum / 9.0;
}

#endif
