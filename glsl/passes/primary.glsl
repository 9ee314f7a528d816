// Pass `primary` (pure ray-traced mode): camera rays find the primary hit
// and write it into the same G-buffer targets the `gbuffer` raster pass
// fills, so every later pass is shared between the two modes. Albedo is
// sRGB-encoded by the same function as in gbuffer_resolve.comp (common/srgb.glsl).
#include "../common/scene.glsl"
#include "../common/hit.glsl"
#include "../common/primary_hit.glsl"
#include "../common/integrator.glsl"
#include "../common/camera_ray.glsl"
#include "../common/srgb.glsl"
#include "../common/gbuffer_pack.glsl"

layout(set = SET_PASS, binding = GB_ALBEDO, rgba8) uniform writeonly image2D gb_albedo;
layout(set = SET_PASS, binding = GB_NORMAL, r32ui) uniform writeonly uimage2D gb_normal;
layout(set = SET_PASS, binding = GB_MATERIAL, rgba8) uniform writeonly image2D gb_material;
layout(set = SET_PASS, binding = GB_HIT, rg32ui) uniform writeonly uimage2D gb_hit;


void primary_pixel(ivec2 px) {
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    vec3 dir;
    RayHit h;
    bool hit = trace_camera_ray(px, dir, h);
    if (!hit) {
        imageStore(gb_hit, px, uvec4(0u));
        return;
    }
    vec3 gn;
    bool back_face;
    g_hit_grad = true;
    camera_uv_gradients(h.instance, h.primitive, px, g_uv_dx, g_uv_dy);
    Surface s = hit_surface(h, frame.camera_pos, dir, pixel_spread_angle() * h.t, gn, back_face);
    g_hit_grad = false;
    imageStore(gb_albedo, px, vec4(srgb_encode(s.base_color), s.occlusion));
    imageStore(gb_normal, px, uvec4(oct_encode(s.normal)));
    imageStore(gb_material, px, vec4(s.metallic, s.roughness, s.transmission, 0.0));
    imageStore(gb_hit, px, uvec4(h.instance + 1u, h.primitive, 0u, 0u));
}
