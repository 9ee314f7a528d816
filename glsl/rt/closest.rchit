#version 460
// Reports the closest hit; nothing is shaded here.
#extension GL_EXT_ray_tracing : require
#include "payload.glsl"

layout(location = 0) rayPayloadInEXT TracePayload payload;
hitAttributeEXT vec2 attribs;

void main() {
    payload.instance = gl_InstanceCustomIndexEXT;
    payload.primitive = gl_PrimitiveID;
    payload.bary = attribs;
    payload.t = gl_HitTEXT;
    payload.hit = 1u;
}
