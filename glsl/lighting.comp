#version 460
// Deferred lighting: G-buffer + exact primary hit -> HDR radiance.
// Direct light from every punctual light (unshadowed here; the ray passes add
// visibility), emission, a constant ambient term from the environment, and
// the environment as background.
#include "common/scene.glsl"
#include "common/env.glsl"
#include "common/brdf.glsl"
#include "common/lights.glsl"
#include "common/primary_hit.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0) uniform sampler2D gb_albedo;
layout(set = 1, binding = 1) uniform sampler2D gb_normal;
layout(set = 1, binding = 2) uniform sampler2D gb_material;
layout(set = 1, binding = 3) uniform sampler2D gb_emissive;
layout(set = 1, binding = 4) uniform usampler2D gb_hit;
layout(set = 1, binding = 5) uniform sampler2D gb_depth;
layout(set = 1, binding = 6, rgba16f) uniform writeonly image2D hdr_out;

vec3 hash_color(uint x) {
    x = (x ^ 61u) ^ (x >> 16u);
    x *= 9u;
    x = x ^ (x >> 4u);
    x *= 0x27d4eb2du;
    x = x ^ (x >> 15u);
    return vec3(x & 255u, (x >> 8u) & 255u, (x >> 16u) & 255u) / 255.0;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;

    vec3 dir = camera_ray_dir(vec2(px) + 0.5);
    uvec2 hit = texelFetch(gb_hit, px, 0).xy;
    if (hit.x == 0u) {
        vec3 bg = frame.debug_view == DEBUG_NONE ? environment(dir) : vec3(0.0);
        imageStore(hdr_out, px, vec4(bg, 1.0));
        return;
    }

    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 nr = texelFetch(gb_normal, px, 0);
    vec4 mat = texelFetch(gb_material, px, 0);
    vec3 emissive = texelFetch(gb_emissive, px, 0).rgb;

    Surface s;
    TriangleWorld tri = triangle_world(hit.x - 1u, hit.y);
    s.position = interpolate(tri, plane_barycentrics(tri, frame.camera_pos, dir));
    s.normal = normalize(nr.xyz);
    s.base_color = albedo.rgb;
    s.occlusion = albedo.a;
    s.roughness = nr.w;
    s.metallic = mat.r;
    s.transmission = mat.g;
    s.ior = 1.0 + mat.b * 2.0;
    s.emissive = emissive;

    vec3 color;
    switch (frame.debug_view) {
    case DEBUG_ALBEDO: color = s.base_color; break;
    case DEBUG_NORMAL: color = s.normal * 0.5 + 0.5; break;
    case DEBUG_DEPTH: {
        // Reversed-Z: depth = znear / distance; show it on a log scale.
        float d = texelFetch(gb_depth, px, 0).r;
        color = vec3(clamp(1.0 + log2(max(d, 1e-8)) / 16.0, 0.0, 1.0));
        break;
    }
    case DEBUG_MATERIAL: color = vec3(s.metallic, s.roughness, s.transmission); break;
    case DEBUG_OBJECT: color = hash_color(instances[hit.x - 1u].object_id + 1u); break;
    default: {
        vec3 v = -dir;
        // Shading normals facing away from the viewer (normal maps at
        // grazing angles) would go black; bend them back to the visible side.
        if (dot(s.normal, v) < 0.0) s.normal = normalize(s.normal - v * (dot(s.normal, v) * 1.01));
        color = s.emissive;
        for (uint i = 0u; i < frame.light_count; ++i) {
            LightSample ls = sample_light(lights[i], s.position);
            color += brdf_eval(s, v, ls.l, ls.irradiance);
        }
        vec3 f0 = surface_f0(s);
        vec3 diffuse = (1.0 - s.metallic) * (1.0 - s.transmission) * s.base_color;
        color += frame.env_ambient * s.occlusion * (diffuse * (1.0 - f0) + f0);
    }
    }
    imageStore(hdr_out, px, vec4(color, 1.0));
}
