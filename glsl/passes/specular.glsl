// Pass `specular`: the reflection / refraction chain that starts at the
// primary hit (Fresnel-weighted branches on an explicit stack, recursion up
// to MAX_DEPTH, importance cutoff MIN_WEIGHT, environment on miss). The
// secondary hits are shaded in full here, direct light and shadow rays
// included.
#include "../common/gbuffer_read.glsl"
#include "../common/integrator.glsl"

layout(set = SET_PASS, binding = SPECULAR_OUT, rgba32f) uniform writeonly image2D specular_out;

void specular_pixel(ivec2 px) {
    PrimaryHit p;
    if (outside_frame(px) || !read_primary(px, p)) return;
    vec3 v = -p.dir;
    float nv = face_viewer(p.s, v);
    g_effects = budget_effects(p.instance, px);
    // The pixel's cone at the primary hit.
    float spread = pixel_spread_angle();
    Cone cone = Cone(spread * distance(frame.camera_pos, p.s.position), spread);
    push_branches(p.s, v, nv, p.gn, p.back_face, vec3(1.0), 0u, cone);
    // A chain the selection started is traced whole.
    g_effects = EFFECT_ALL;
    imageStore(specular_out, px, vec4(trace_branches(), 1.0));
    budget_count_rays(p.instance);
}
