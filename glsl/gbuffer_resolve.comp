#version 460
// Pass `gbuffer_resolve` (hybrid mode, raster visibility): the raster pass
// stored only each pixel's (instance + 1, primitive); this fills the
// material targets from that triangle (common/gbuffer_resolve.glsl).
#include "common/gbuffer_resolve.glsl"

layout(set = SET_PASS, binding = GB_HIT, rg32ui) uniform readonly uimage2D gb_hit;

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), frame.resolution))) return;
    uvec2 id = imageLoad(gb_hit, px).xy;
    // No hit: readers look at nothing but the hit id there.
    if (id.x == 0u) return;
    resolve_gbuffer(px, id.x - 1u, id.y);
}
