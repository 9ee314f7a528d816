// Environment lookup: the background where camera rays miss and the
// radiance of reflection / refraction rays that miss.
#ifndef ENV_GLSL
#define ENV_GLSL
#include "scene.glsl"
#include "math.glsl"

// Equirectangular: +Y up, u = 0.5 looks down -Z, rotation turns about +Y.
vec2 env_uv(vec3 d) {
    float phi = atan(d.x, -d.z) + frame.env_rotation;
    float u = phi / (2.0 * PI) + 0.5;
    float v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return vec2(u, v);
}

vec3 environment(vec3 dir) {
    if (frame.has_env_map != 0u) {
        return textureLod(env_map, env_uv(dir), 0.0).rgb * frame.env_intensity;
    }
    return frame.env_color * frame.env_intensity;
}

#endif
