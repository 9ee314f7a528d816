// Traversal with VK_KHR_ray_query. Implements the tracing interface's
//   bool trace_ray(vec3 o, vec3 d, float tmax, bool shadow, out RayHit hit, out vec3 tr)
// (common/trace.glsl builds trace_closest and trace_shadow on it).
#ifndef TRACE_QUERY_GLSL
#define TRACE_QUERY_GLSL
#extension GL_EXT_ray_query : require
#include "../common/hit.glsl"

layout(set = SET_TRACE, binding = TRACE_TLAS) uniform accelerationStructureEXT tlas;


// Closest hit, or (`shadow`) whether the ray is blocked, with the transmittance `tr` of what it crossed.
// Both kinds in one loop: lavapipe inlines its traversal at every rayQueryProceedEXT.
bool trace_ray(vec3 o, vec3 d, float tmax, bool shadow, out RayHit hit, out vec3 tr) {
    tr = vec3(1.0);
    hit = RayHit(0u, 0u, vec2(0.0), tmax);
    rayQueryEXT q;
    uint flags = shadow ? gl_RayFlagsTerminateOnFirstHitEXT : gl_RayFlagsNoneEXT;
    rayQueryInitializeEXT(q, tlas, flags, shadow ? MASK_SHADOW : MASK_VISIBLE, o, 0.0, d, tmax);
    while (rayQueryProceedEXT(q)) {
        // Only non-opaque instances (alpha mask, blend, transmission) get here.
        uint inst = rayQueryGetIntersectionInstanceCustomIndexEXT(q, false);
        uint prim = rayQueryGetIntersectionPrimitiveIndexEXT(q, false);
        vec2 b = rayQueryGetIntersectionBarycentricsEXT(q, false);
        if (shadow) {
            vec3 t = occluder_transmittance(inst, prim, b);
            if (all(equal(t, vec3(0.0)))) {
                rayQueryConfirmIntersectionEXT(q);  // blocks; terminates the query
            } else {
                tr *= t;  // order-independent product of crossings
            }
        } else if (hit_alpha_passes(inst, prim, b, rayQueryGetIntersectionTEXT(q, false))) {
            rayQueryConfirmIntersectionEXT(q);
        }
    }
    // Query the committed type before reading any committed data: reading
    // it after a miss has crashed llvmpipe (wgpu issue #6731).
    if (rayQueryGetIntersectionTypeEXT(q, true) != gl_RayQueryCommittedIntersectionTriangleEXT) {
        return false;
    }
    if (shadow) return true;
    hit.instance = rayQueryGetIntersectionInstanceCustomIndexEXT(q, true);
    hit.primitive = rayQueryGetIntersectionPrimitiveIndexEXT(q, true);
    hit.bary = rayQueryGetIntersectionBarycentricsEXT(q, true);
    hit.t = rayQueryGetIntersectionTEXT(q, true);
    return true;
}

#endif
