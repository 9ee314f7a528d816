// Reconstructs the exact primary hit from the G-buffer's (instance,
// primitive): the camera ray through the pixel centre intersected with the
// stored triangle. Ray origins later start from this point, not from depth.
#ifndef PRIMARY_HIT_GLSL
#define PRIMARY_HIT_GLSL
#include "scene.glsl"

struct TriangleWorld {
    vec3 p0, p1, p2;
};

TriangleWorld triangle_world(uint instance, uint primitive) {
    Instance inst = instances[instance];
    uint base = inst.first_index + 3u * primitive;
    TriangleWorld t;
    t.p0 = (inst.world * vec4(vertices[inst.vertex_offset + indices[base + 0u]].position, 1.0)).xyz;
    t.p1 = (inst.world * vec4(vertices[inst.vertex_offset + indices[base + 1u]].position, 1.0)).xyz;
    t.p2 = (inst.world * vec4(vertices[inst.vertex_offset + indices[base + 2u]].position, 1.0)).xyz;
    return t;
}

// Built from the view rotation and focal terms, not the inverse view-projection, to stay precise far
// from the origin.
vec3 camera_ray_dir(vec2 pixel) {
    vec2 ndc = pixel / vec2(frame.resolution) * 2.0 - 1.0;
    vec3 dv = vec3(ndc.x / frame.proj[0][0], ndc.y / frame.proj[1][1], -1.0);
    return normalize(transpose(mat3(frame.view)) * dv);
}

// Apex angle of one pixel's ray cone.
float pixel_spread_angle() {
    return atan(2.0 / (abs(frame.proj[1][1]) * float(frame.resolution.y)));
}

// Barycentrics (b1, b2) of the ray/triangle-plane intersection, anywhere in
// the plane (for screen-space derivatives).
vec2 plane_barycentrics_unclamped(TriangleWorld t, vec3 o, vec3 d) {
    vec3 e1 = t.p1 - t.p0;
    vec3 e2 = t.p2 - t.p0;
    vec3 pv = cross(d, e2);
    float det = dot(e1, pv);
    if (abs(det) < 1e-30) return vec2(1.0 / 3.0);
    float inv = 1.0 / det;
    vec3 tv = o - t.p0;
    vec3 qv = cross(tv, e1);
    return vec2(dot(tv, pv), dot(d, qv)) * inv;
}

// Barycentrics (b1, b2) of the ray/triangle-plane intersection, clamped into
// the triangle so the point is on the surface even for edge pixels whose
// centre the rasterizer covered by the tie-breaking rule.
vec2 plane_barycentrics(TriangleWorld t, vec3 o, vec3 d) {
    vec2 b = plane_barycentrics_unclamped(t, o, d);
    float u = clamp(b.x, 0.0, 1.0);
    float v = clamp(b.y, 0.0, 1.0);
    float s = u + v;
    if (s > 1.0) { u /= s; v /= s; }
    return vec2(u, v);
}

vec3 interpolate(TriangleWorld t, vec2 b) {
    return t.p0 + (t.p1 - t.p0) * b.x + (t.p2 - t.p0) * b.y;
}

#endif
