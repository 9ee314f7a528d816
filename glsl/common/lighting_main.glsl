#ifndef LIGHTING_MAIN_GLSL
#define LIGHTING_MAIN_GLSL
// The per-pixel lighting / integrator program, shared by the compute entry
// point (lighting.comp) and the ray-generation shader (lighting.rgen).
// Variants (glsl/variants.txt):
//   TRACE_NONE (default)  deferred shading, no rays
//   TRACE_QUERY           ray-query traversal (compute)
//   TRACE_COMPUTE         our BVH traversal (compute)
//   TRACE_PIPELINE        traceRayEXT (ray-generation shader)
//   PURE_RT               camera rays traced too, no G-buffer
#if !defined(TRACE_QUERY) && !defined(TRACE_COMPUTE) && !defined(TRACE_PIPELINE)
#define TRACE_NONE
#endif
#include "scene.glsl"
#include "hit.glsl"
#ifdef TRACE_QUERY
#include "../trace/query.glsl"
#endif
#ifdef TRACE_COMPUTE
#include "../trace/compute.glsl"
#endif
#ifdef TRACE_PIPELINE
#include "../trace/pipeline.glsl"
#endif
#include "integrator.glsl"
#include "primary_hit.glsl"


#ifndef PURE_RT
layout(set = 1, binding = 0) uniform sampler2D gb_albedo;
layout(set = 1, binding = 1) uniform sampler2D gb_normal;
layout(set = 1, binding = 2) uniform sampler2D gb_material;
layout(set = 1, binding = 3) uniform sampler2D gb_emissive;
layout(set = 1, binding = 4) uniform usampler2D gb_hit;
layout(set = 1, binding = 5) uniform sampler2D gb_depth;
#endif
layout(set = 1, binding = 6, rgba32f) uniform writeonly image2D hdr_out;

vec3 hash_color(uint x) {
    x = (x ^ 61u) ^ (x >> 16u);
    x *= 9u;
    x = x ^ (x >> 4u);
    x *= 0x27d4eb2du;
    x = x ^ (x >> 15u);
    return vec3(x & 255u, (x >> 8u) & 255u, (x >> 16u) & 255u) / 255.0;
}

// Shades pixel `px`: the whole per-pixel program of every backend.
void shade_pixel(ivec2 px) {
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    vec3 dir = camera_ray_dir(vec2(px) + 0.5);

    // The primary hit: from the G-buffer (hybrid) or from a camera ray (pure RT).
    Surface s;
    vec3 gn;
    bool back_face;
    uint instance;
#ifdef PURE_RT
    RayHit h;
    count_ray(0u);
    if (!trace_closest(frame.camera_pos, dir, RAY_TMAX, h)) {
        imageStore(hdr_out, px, vec4(environment(dir), 1.0));
        return;
    }
    instance = h.instance;
    s = hit_surface(h, frame.camera_pos, dir, gn, back_face);
    float depth = frame.znear / max(h.t * dot(dir, -transpose(mat3(frame.view))[2]), 1e-30);
#else
    uvec2 hit = texelFetch(gb_hit, px, 0).xy;
    if (hit.x == 0u) {
        vec3 bg = frame.debug_view == DEBUG_NONE ? environment(dir) : vec3(0.0);
        imageStore(hdr_out, px, vec4(bg, 1.0));
        return;
    }
    instance = hit.x - 1u;
    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 nr = texelFetch(gb_normal, px, 0);
    vec4 mat = texelFetch(gb_material, px, 0);
    TriangleWorld tri = triangle_world(instance, hit.y);
    s.position = interpolate(tri, plane_barycentrics(tri, frame.camera_pos, dir));
    vec3 tn = cross(tri.p1 - tri.p0, tri.p2 - tri.p0);
    tn = dot(tn, tn) > 0.0 ? normalize(tn) : -dir;
    back_face = dot(tn, dir) > 0.0;
    gn = back_face ? -tn : tn;
    s.normal = normalize(nr.xyz);
    s.base_color = albedo.rgb;
    s.occlusion = albedo.a;
    s.roughness = nr.w;
    s.metallic = mat.r;
    s.transmission = mat.g;
    s.ior = materials[instances[instance].material].ior;
    s.emissive = texelFetch(gb_emissive, px, 0).rgb;
    float depth = texelFetch(gb_depth, px, 0).r;
#endif

    vec3 color;
    switch (frame.debug_view) {
    case DEBUG_ALBEDO: color = s.base_color; break;
    case DEBUG_NORMAL: color = s.normal * 0.5 + 0.5; break;
    // Reversed-Z: depth = znear / distance; shown on a log scale.
    case DEBUG_DEPTH: color = vec3(clamp(1.0 + log2(max(depth, 1e-8)) / 16.0, 0.0, 1.0)); break;
    case DEBUG_MATERIAL: color = vec3(s.metallic, s.roughness, s.transmission); break;
    case DEBUG_OBJECT: color = hash_color(instances[instance].object_id + 1u); break;
    default:
        color = shade(s, -dir, gn, back_face, vec3(1.0), 0u);
        color += trace_branches();
    }
    imageStore(hdr_out, px, vec4(color, 1.0));
}

#endif
