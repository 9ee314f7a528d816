// The primary hit as every pass after `gbuffer` / `primary` sees it: the
// G-buffer targets (set 1, bindings GB_*), with the exact hit point
// reconstructed from the stored (instance, primitive) by intersecting the
// camera ray with that triangle. Both modes write the same targets, so the
// passes that read them do not know which one ran.
#ifndef GBUFFER_READ_GLSL
#define GBUFFER_READ_GLSL
#include "scene.glsl"
#include "brdf.glsl"
#include "primary_hit.glsl"
#include "offset.glsl"
#include "srgb.glsl"

layout(set = SET_PASS, binding = GB_ALBEDO) uniform sampler2D gb_albedo;
layout(set = SET_PASS, binding = GB_NORMAL) uniform sampler2D gb_normal;
layout(set = SET_PASS, binding = GB_MATERIAL) uniform sampler2D gb_material;
layout(set = SET_PASS, binding = GB_EMISSIVE) uniform sampler2D gb_emissive;
layout(set = SET_PASS, binding = GB_HIT) uniform usampler2D gb_hit;

struct PrimaryHit {
    Surface s;
    vec3 dir;       // camera ray direction through the pixel centre
    vec3 gn;        // unit geometric normal on the viewer's side
    bool back_face;
    uint instance;
};

// False where the camera ray through `px` hit nothing (hit id 0).
bool read_primary(ivec2 px, out PrimaryHit p) {
    p.dir = camera_ray_dir(vec2(px) + 0.5);
    uvec2 hit = texelFetch(gb_hit, px, 0).xy;
    if (hit.x == 0u) return false;
    p.instance = hit.x - 1u;
    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 nr = texelFetch(gb_normal, px, 0);
    vec4 mat = texelFetch(gb_material, px, 0);
    TriangleWorld tri = triangle_world(p.instance, hit.y);
    p.s.position = interpolate(tri, plane_barycentrics(tri, frame.camera_pos, p.dir));
    p.s.extent = triangle_extent(tri.p0, tri.p1, tri.p2);
    vec3 tn = cross(tri.p1 - tri.p0, tri.p2 - tri.p0);
    tn = dot(tn, tn) > 0.0 ? normalize(tn) : -p.dir;
    p.back_face = dot(tn, p.dir) > 0.0;
    p.gn = p.back_face ? -tn : tn;
    p.s.normal = normalize(nr.xyz);
    p.s.base_color = srgb_decode(albedo.rgb);
    p.s.occlusion = albedo.a;
    p.s.roughness = nr.w;
    p.s.metallic = mat.r;
    p.s.transmission = mat.g;
    p.s.ior = materials[instances[p.instance].material].ior;
    p.s.emissive = texelFetch(gb_emissive, px, 0).rgb;
    return true;
}

bool outside_frame(ivec2 px) {
    return any(greaterThanEqual(uvec2(px), frame.resolution));
}

#endif
