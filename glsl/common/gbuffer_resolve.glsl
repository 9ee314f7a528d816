// The G-buffer's material targets of pixel `px` from its primary hit, as the old G-buffer fragment
// stage made them (perspective-correct barycentrics at the pixel centre, the rasterizer's per-quad uv
// gradients, normal flipped on back faces by screen winding). Needs only the pixel's own hit, so
// `gbuffer_resolve` (raster) and `visibility_trace` (traced) write the same bytes.
#ifndef GBUFFER_RESOLVE_GLSL
#define GBUFFER_RESOLVE_GLSL
#include "scene.glsl"
#include "hit.glsl"
#include "srgb.glsl"
#include "gbuffer_pack.glsl"

layout(set = SET_PASS, binding = GB_ALBEDO, rgba8) uniform writeonly image2D gb_albedo;
layout(set = SET_PASS, binding = GB_NORMAL, r32ui) uniform writeonly uimage2D gb_normal;
layout(set = SET_PASS, binding = GB_MATERIAL, rgba8) uniform writeonly image2D gb_material;

void resolve_gbuffer(ivec2 px, uint instance, uint primitive) {
    Instance inst = instances[instance];
    Material m = materials[inst.material];
    TriangleWorld tri = triangle_world(instance, primitive);
    vec3 dir = camera_ray_dir(vec2(px) + 0.5);
    vec2 b = plane_barycentrics(tri, frame.camera_pos, dir);
    HitVertices hv = hit_vertices(inst, primitive);
    vec3 w = bary3(b);
    vec3 n = mat3(inst.normal_matrix) * (hv.v0.normal * w.x + hv.v1.normal * w.y + hv.v2.normal * w.z);
    vec4 t4 = hv.v0.tangent * w.x + hv.v1.tangent * w.y + hv.v2.tangent * w.z;
    vec4 tangent = vec4(mat3(inst.world) * t4.xyz, t4.w);
    vec2 uv = hit_uv(hv, b);

    // Derivatives are per 2x2 quad (llvmpipe: top-left pixel to its right and lower neighbours, on the
    // triangle's plane), so a quad picks one mip level.
    ivec2 q = px & ~1;
    vec2 c = vec2(q) + 0.5;
    vec2 uv00 = hit_uv(hv, plane_barycentrics_unclamped(tri, frame.camera_pos, camera_ray_dir(c)));
    g_uv_dx = hit_uv(hv, plane_barycentrics_unclamped(tri, frame.camera_pos, camera_ray_dir(c + vec2(1.0, 0.0)))) - uv00;
    g_uv_dy = hit_uv(hv, plane_barycentrics_unclamped(tri, frame.camera_pos, camera_ray_dir(c + vec2(0.0, 1.0)))) - uv00;
    g_hit_grad = true;
    Surface s;
    float alpha;
    material_eval(m, uv, s, alpha);
    n = dot(n, n) > 1e-20 ? normalize(n) : vec3(0.0, 1.0, 0.0);
    bool mirrored = determinant(mat3(inst.world)) < 0.0;
    bool away = dot(cross(tri.p1 - tri.p0, tri.p2 - tri.p0), dir) > 0.0;
    // The world-space cross product already reflects a mirroring transform, which the raster undid by
    // swapping the front face.
    if (away != mirrored) n = -n;
    n = apply_normal_map(m, uv, n, tangent);
    g_hit_grad = false;

    imageStore(gb_albedo, px, vec4(srgb_encode(s.base_color), s.occlusion));
    imageStore(gb_normal, px, uvec4(oct_encode(n)));
    imageStore(gb_material, px, vec4(s.metallic, s.roughness, s.transmission, 0.0));
}
#endif
