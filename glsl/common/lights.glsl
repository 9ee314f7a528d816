// Punctual lights (KHR_lights_punctual): direction to the light and the
// irradiance it delivers, before visibility.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL
#include "scene.glsl"

struct LightSample {
    vec3 l;          // unit vector from the surface to the light
    float distance;  // to the light (infinite for directional)
    vec3 irradiance; // perpendicular to l, before n.l
};

LightSample sample_light(Light light, vec3 p) {
    LightSample ls;
    if (light.type == LIGHT_DIRECTIONAL) {
        ls.l = -light.direction;
        ls.distance = 1e30;
        ls.irradiance = light.radiance;
        return ls;
    }
    vec3 to_light = light.position - p;
    float d2 = max(dot(to_light, to_light), 1e-12);
    float d = sqrt(d2);
    ls.l = to_light / d;
    ls.distance = d;
    float atten = 1.0 / d2;
    if (light.range > 0.0) {
        // glTF's recommended smooth window to zero at the range.
        float r = d / light.range;
        float w = clamp(1.0 - r * r * r * r, 0.0, 1.0);
        atten *= w * w;
    }
    if (light.type == LIGHT_SPOT) {
        float cd = dot(light.direction, -ls.l);
        float t = clamp(cd * light.spot_scale + light.spot_offset, 0.0, 1.0);
        atten *= t * t;
    }
    ls.irradiance = light.radiance * atten;
    return ls;
}

#endif
