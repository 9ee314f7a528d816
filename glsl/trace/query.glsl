// Traversal with VK_KHR_ray_query. Implements the tracing interface:
//   bool trace_closest(vec3 o, vec3 d, float tmax, out RayHit hit)
//   vec3 trace_shadow(vec3 o, vec3 d, float tmax)   -> transmittance
#ifndef TRACE_QUERY_GLSL
#define TRACE_QUERY_GLSL
#extension GL_EXT_ray_query : require
#include "../common/hit.glsl"

layout(set = SET_TRACE, binding = TRACE_TLAS) uniform accelerationStructureEXT tlas;


bool trace_closest(vec3 o, vec3 d, float tmax, out RayHit hit) {
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, gl_RayFlagsNoneEXT, MASK_VISIBLE, o, 0.0, d, tmax);
    while (rayQueryProceedEXT(q)) {
        // Only non-opaque instances (alpha mask, blend, transmission) get here.
        uint inst = rayQueryGetIntersectionInstanceCustomIndexEXT(q, false);
        uint prim = rayQueryGetIntersectionPrimitiveIndexEXT(q, false);
        vec2 b = rayQueryGetIntersectionBarycentricsEXT(q, false);
        float t = rayQueryGetIntersectionTEXT(q, false);
        if (hit_alpha_passes(inst, prim, b, t)) rayQueryConfirmIntersectionEXT(q);
    }
    // Query the committed type before reading any committed data: reading
    // it after a miss has crashed llvmpipe (wgpu issue #6731).
    if (rayQueryGetIntersectionTypeEXT(q, true) != gl_RayQueryCommittedIntersectionTriangleEXT) {
        return false;
    }
    hit.instance = rayQueryGetIntersectionInstanceCustomIndexEXT(q, true);
    hit.primitive = rayQueryGetIntersectionPrimitiveIndexEXT(q, true);
    hit.bary = rayQueryGetIntersectionBarycentricsEXT(q, true);
    hit.t = rayQueryGetIntersectionTEXT(q, true);
    return true;
}

vec3 trace_shadow(vec3 o, vec3 d, float tmax) {
    vec3 transmittance = vec3(1.0);
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, gl_RayFlagsTerminateOnFirstHitEXT, MASK_SHADOW, o, 0.0, d, tmax);
    while (rayQueryProceedEXT(q)) {
        uint inst = rayQueryGetIntersectionInstanceCustomIndexEXT(q, false);
        uint prim = rayQueryGetIntersectionPrimitiveIndexEXT(q, false);
        vec2 b = rayQueryGetIntersectionBarycentricsEXT(q, false);
        vec3 t = occluder_transmittance(inst, prim, b);
        if (all(equal(t, vec3(0.0)))) {
            rayQueryConfirmIntersectionEXT(q);  // blocks; terminates the query
        } else {
            transmittance *= t;  // order-independent product of crossings
        }
    }
    if (rayQueryGetIntersectionTypeEXT(q, true) != gl_RayQueryCommittedIntersectionNoneEXT) {
        return vec3(0.0);
    }
    return transmittance;
}

#endif
