// Payload shared by the ray-generation shader and the hit/miss shaders of
// the RT-pipeline backend. Hit shaders only report; shading stays in the
// shared integrator.
#ifndef PAYLOAD_GLSL
#define PAYLOAD_GLSL
struct TracePayload {
    uint instance;
    uint primitive;
    vec2 bary;
    float t;
    uint hit;            // 1 = something was hit (for shadow rays: blocked)
    vec3 transmittance;  // shadow rays: product over transmissive crossings
    // A pure-RT camera ray's pixel (x | y << 16), for its alpha tests' LOD;
    // NOT_A_CAMERA_RAY otherwise.
    uint camera_pixel;
    // A reflection/refraction ray's cone (g_alpha_cone): its alpha tests' LOD.
    vec2 alpha_cone;
    // Shadow rays: 1 where the ray-generation shader's g_opaque_occluders
    // is set (glass blocks), for the any-hit shader.
    uint opaque;
};
const uint NOT_A_CAMERA_RAY = 0xffffffffu;
// Hit groups: HIT_GROUP_* in generated/shared.glsl.
#endif
