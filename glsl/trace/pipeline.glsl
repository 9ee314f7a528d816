// Traversal with VK_KHR_ray_tracing_pipeline (traceRayEXT from the
// ray-generation shader): trace_closest, trace_shadow and trace_ray (common/trace.glsl).
#ifndef TRACE_PIPELINE_GLSL
#define TRACE_PIPELINE_GLSL
#extension GL_EXT_ray_tracing : require
#include "../common/hit.glsl"
#include "../rt/payload.glsl"

layout(set = SET_TRACE, binding = TRACE_TLAS) uniform accelerationStructureEXT tlas;
layout(location = 0) rayPayloadEXT TracePayload payload;


bool trace_closest(vec3 o, vec3 d, float tmax, out RayHit hit) {
    payload.hit = 0u;
    payload.camera_pixel =
        g_camera_ray ? uint(g_camera_pixel.x) | (uint(g_camera_pixel.y) << 16) : NOT_A_CAMERA_RAY;
    payload.alpha_cone = g_alpha_cone;
    traceRayEXT(tlas, gl_RayFlagsNoneEXT, MASK_VISIBLE, HIT_GROUP_VISIBLE, HIT_GROUP_STRIDE, 0u, o, 0.0, d, tmax, 0);
    hit = RayHit(payload.instance, payload.primitive, payload.bary, payload.t);
    return payload.hit != 0u;
}

vec3 trace_shadow(vec3 o, vec3 d, float tmax) {
    // Assume blocked; the miss shader clears it. Opaque hits (and accepted
    // any-hits) end the ray without a miss.
    payload.hit = 1u;
    payload.transmittance = vec3(1.0);
    payload.camera_pixel = NOT_A_CAMERA_RAY;
    payload.alpha_cone = vec2(0.0);
    payload.opaque = g_opaque_occluders ? 1u : 0u;
    uint flags = gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT;
    traceRayEXT(tlas, flags, MASK_SHADOW, HIT_GROUP_SHADOW, HIT_GROUP_STRIDE, 0u, o, 0.0, d, tmax, 0);
    return payload.hit != 0u ? vec3(0.0) : payload.transmittance;
}

// traceRayEXT is a call into the pipeline's shaders, not inlined traversal: two call sites cost nothing.
bool trace_ray(vec3 o, vec3 d, float tmax, bool shadow, out RayHit hit, out vec3 tr) {
    tr = vec3(1.0);
    hit = RayHit(0u, 0u, vec2(0.0), tmax);
    if (!shadow) return trace_closest(o, d, tmax, hit);
    tr = trace_shadow(o, d, tmax);
    return all(equal(tr, vec3(0.0)));
}

#endif
