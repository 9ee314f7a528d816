// Pass `direct`: direct light from every punctual light at the primary hit,
// with (transmittance) shadow rays when SHADOWS is on. Misses are left
// unwritten: `composite` does not read them.
#include "../common/gbuffer_read.glsl"
#include "../common/integrator.glsl"

layout(set = SET_PASS, binding = DIRECT_OUT, rgba32f) uniform writeonly image2D direct_out;

void direct_pixel(ivec2 px) {
    PrimaryHit p;
    if (outside_frame(px) || !read_primary(px, p)) return;
    vec3 v = -p.dir;
    face_viewer(p.s, v);
    g_effects = budget_effects(p.instance, px);
    imageStore(direct_out, px, vec4(direct_light(p.s, v, p.gn), 1.0));
    budget_count_rays(p.instance);
}
