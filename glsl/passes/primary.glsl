// Pass `primary` (pure ray-traced mode): camera rays find the primary hit
// and write it into the same G-buffer targets the `gbuffer` raster pass
// fills, so every later pass is shared between the two modes. Albedo is
// sRGB-encoded by the same function as in gbuffer.frag (common/srgb.glsl).
#include "../common/scene.glsl"
#include "../common/hit.glsl"
#include "../common/primary_hit.glsl"
#include "../common/integrator.glsl"
#include "../common/srgb.glsl"

layout(set = SET_PASS, binding = GB_ALBEDO, rgba8) uniform writeonly image2D gb_albedo;
layout(set = SET_PASS, binding = GB_NORMAL, rgba16f) uniform writeonly image2D gb_normal;
layout(set = SET_PASS, binding = GB_MATERIAL, rgba8) uniform writeonly image2D gb_material;
layout(set = SET_PASS, binding = GB_EMISSIVE, rgba16f) uniform writeonly image2D gb_emissive;
layout(set = SET_PASS, binding = GB_HIT, rg32ui) uniform writeonly uimage2D gb_hit;


// The uv gradients the rasterizer would use at `px` (differences to the
// neighbouring pixels, whose camera rays meet the hit triangle's plane), so
// pure RT filters the primary hit's textures exactly like the G-buffer pass.
void primary_uv_gradients(RayHit h, ivec2 px, out vec2 dx, out vec2 dy) {
    TriangleWorld t = triangle_world(h.instance, h.primitive);
    HitVertices hv = hit_vertices(instances[h.instance], h.primitive);
    vec2 c = vec2(px) + 0.5;
    vec2 b0 = plane_barycentrics_unclamped(t, frame.camera_pos, camera_ray_dir(c));
    vec2 bx = plane_barycentrics_unclamped(t, frame.camera_pos, camera_ray_dir(c + vec2(1.0, 0.0)));
    vec2 by = plane_barycentrics_unclamped(t, frame.camera_pos, camera_ray_dir(c + vec2(0.0, 1.0)));
    vec2 uv0 = hit_uv(hv, b0);
    dx = hit_uv(hv, bx) - uv0;
    dy = hit_uv(hv, by) - uv0;
}

void primary_pixel(ivec2 px) {
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    vec3 dir = camera_ray_dir(vec2(px) + 0.5);
    RayHit h;
    count_ray(RAY_KIND_CAMERA);
    if (!trace_closest(frame.camera_pos, dir, RAY_TMAX, h)) {
        imageStore(gb_hit, px, uvec4(0u));
        return;
    }
    vec3 gn;
    bool back_face;
    g_hit_grad = true;
    primary_uv_gradients(h, px, g_uv_dx, g_uv_dy);
    Surface s = hit_surface(h, frame.camera_pos, dir, pixel_spread_angle() * h.t, gn, back_face);
    g_hit_grad = false;
    imageStore(gb_albedo, px, vec4(srgb_encode(s.base_color), s.occlusion));
    imageStore(gb_normal, px, vec4(s.normal, s.roughness));
    imageStore(gb_material, px, vec4(s.metallic, s.transmission, clamp((s.ior - 1.0) * 0.5, 0.0, 1.0), 0.0));
    imageStore(gb_emissive, px, vec4(s.emissive, 0.0));
    imageStore(gb_hit, px, uvec4(h.instance + 1u, h.primitive, 0u, 0u));
}
