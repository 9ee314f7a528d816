// Pass `visibility_trace` (hybrid mode, traced primary visibility): the
// camera ray through each pixel centre finds the primary hit, stores
// (instance + 1, primitive) in the hit target, the visibility buffer the
// raster `gbuffer` pass would have written, and resolves the material
// targets from it right away with the code `gbuffer_resolve` runs on the
// raster's hits (common/gbuffer_resolve.glsl): the same bytes, without a
// second pass over the screen. The ray is the one `primary` traces (same
// direction, same alpha test with the same camera-ray mip selection), so
// alpha-masked cut-outs fall where the raster's alpha test puts them.
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
    // Hit id 0: the camera ray missed (as the raster pass's clear value).
    imageStore(gb_hit, px, hit ? uvec4(h.instance + 1u, h.primitive, 0u, 0u) : uvec4(0u));
    if (hit) resolve_gbuffer(px, h.instance, h.primitive);
}
