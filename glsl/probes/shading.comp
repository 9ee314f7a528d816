#version 460
// Evaluates the shading functions the renderer uses (BRDF, Fresnel,
// refraction, ray offset, tone curves, eye adaptation) on host-given inputs, so tests can check the
// compiled GLSL itself against closed forms (tests/render/shading_closed_form.rs).
// Not part of any frame.
#extension GL_EXT_scalar_block_layout : require
#include "../common/types.glsl"
#include "../common/brdf.glsl"
#include "../common/fresnel.glsl"
#include "../common/offset.glsl"
#include "../common/tonemap.glsl"
#include "../common/exposure.glsl"
#include "../common/gbuffer_pack.glsl"

layout(local_size_x = 64) in;

struct ProbeCase {
    uint op;
    float a;
    float b;
    float c;
    vec4 p;
    vec4 q;
    vec4 r;
};

layout(scalar, set = SET_PROBE, binding = PROBE_IN) readonly buffer Cases { ProbeCase cases[]; };
layout(scalar, set = SET_PROBE, binding = PROBE_OUT) writeonly buffer Results { vec4 results[]; };
layout(push_constant) uniform Push { uint count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    ProbeCase k = cases[i];
    vec4 o = vec4(0.0);
    if (k.op == PROBE_FRESNEL) {
        o.x = fresnel_dielectric(k.a, k.b);
    } else if (k.op == PROBE_SCHLICK) {
        o.xyz = f_schlick(k.p.xyz, k.a);
    } else if (k.op == PROBE_BRDF) {
        // Surface at the origin with normal +Z; v = q, l = r, irradiance 1.
        Surface s;
        s.position = vec3(0.0);
        s.extent = 0.0;
        s.normal = vec3(0.0, 0.0, 1.0);
        s.base_color = k.p.xyz;
        s.metallic = k.a;
        s.roughness = k.b;
        s.occlusion = 1.0;
        s.emissive = vec3(0.0);
        s.transmission = k.c;
        s.ior = k.p.w;
        no_layer_extensions(s);
        o.xyz = brdf_eval(s, k.q.xyz, k.r.xyz, vec3(1.0));
    } else if (k.op == PROBE_GGX) {
        // a = n.h, b = alpha², p.xy = (n.v, n.l).
        o.x = d_ggx(k.a, k.b);
        o.y = v_smith_ggx_correlated(k.p.x, k.p.y, k.b);
    } else if (k.op == PROBE_OFFSET) {
        o.xyz = offset_ray(k.p.xyz, k.q.xyz, k.p.w);
    } else if (k.op == PROBE_TONEMAP) {
        // Operator b (TONEMAP_*) on colour p, white point c.
        o.xyz = tonemap_apply(uint(k.b), k.p.xyz, k.c);
    } else if (k.op == PROBE_ADAPT) {
        // p.z adaptation steps of c seconds from a towards b: x log-average,
        // y histogram at speeds p.xy (brighten, darken).
        o.xy = vec2(k.a);
        for (uint s = 0u; s < uint(k.p.z); s++) {
            o.x = adapt_log_average(o.x, k.b, k.c);
            o.y = adapt_histogram(o.y, k.b, k.c, k.p.x, k.p.y);
        }
    } else if (k.op == PROBE_OCTAHEDRAL) {
        // The G-buffer's normal round trip; w the raw bits (as a float).
        uint bits = oct_encode(k.p.xyz);
        o = vec4(oct_decode(bits), uintBitsToFloat(bits));
    } else if (k.op == PROBE_REFRACT) {
        o.xyz = refract_dir(k.p.xyz, k.q.xyz, k.a);
    }
    results[i] = o;
}
