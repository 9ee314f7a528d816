// Pass `visibility_trace` (hybrid mode, traced primary visibility): writes the hit target the raster
// `gbuffer` pass would, then resolves the material targets right away with gbuffer_resolve's code
// (same bytes, no second screen pass). Same ray and camera-ray alpha mip as `primary`, so alpha
// cut-outs fall where the raster's alpha test puts them.
#include "../common/scene.glsl"
#include "../common/hit.glsl"
#include "../common/primary_hit.glsl"
#include "../common/integrator.glsl"
#include "../common/camera_ray.glsl"
#include "../common/gbuffer_resolve.glsl"

layout(set = SET_PASS, binding = GB_HIT, rg32ui) uniform writeonly uimage2D gb_hit;

void visibility_pixel(ivec2 px) {
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    vec3 dir;
    RayHit h;
    bool hit = trace_camera_ray(px, dir, h);
    // Hit id 0 is a miss, as the raster pass's clear value.
    imageStore(gb_hit, px, hit ? uvec4(h.instance + 1u, h.primitive, 0u, 0u) : uvec4(0u));
    if (hit) resolve_gbuffer(px, h.instance, h.primitive);
}
