// Pass `specular`: the reflection / refraction chain that starts at the
// primary hit (Fresnel-weighted branches on an explicit stack, recursion up
// to MAX_DEPTH, importance cutoff MIN_WEIGHT, environment on miss). The
// secondary hits are shaded in full here, direct light and shadow rays
// included. Two kernels (render/passes/compacted.rs): `specular_select`
// finds the pixels whose primary hit spawns a branch and lists them
// (common/work_list.glsl); the chain kernel traces the listed pixels.
#include "../common/gbuffer_read.glsl"
#include "../common/integrator.glsl"
#include "../common/work_list.glsl"

layout(set = SET_PASS, binding = SPECULAR_OUT, rgba32f) uniform writeonly image2D specular_out;

// Pushes the branches of the primary hit at `px` (with the budget's effects
// for its object); false where the pixel has no primary hit.
bool specular_root(ivec2 px, out PrimaryHit p) {
    if (!read_primary(px, p)) return false;
    vec3 v = -p.dir;
    float nv = face_viewer(p.s, v);
    g_effects = budget_effects(p.instance, px);
    // The pixel's cone at the primary hit.
    float spread = pixel_spread_angle();
    Cone cone = Cone(spread * distance(frame.camera_pos, p.s.position), spread);
    push_branches(p.s, v, nv, p.gn, p.back_face, vec3(1.0), 0u, cone);
    return true;
}

// Select kernel, one invocation per pixel: a hit whose material spawns no
// branch gets no specular radiance now, the others are listed. Decided from
// the G-buffer's material terms alone, without reconstructing the hit: the
// chain kernel reads the whole hit of a listed pixel anyway (and writes
// zero where its branches fall under MIN_WEIGHT).
void specular_select(ivec2 px) {
    uvec2 hit;
    Surface s;
    if (outside_frame(px) || !read_primary_material(px, hit, s)) return;
    g_effects = budget_effects(hit.x - 1u, px);
    if (spawns_branches(s, 0u)) {
        work_append(px);
    } else {
        imageStore(specular_out, px, vec4(0.0, 0.0, 0.0, 1.0));
    }
}

// Listed kernel, entry `i`: the pixel's branches pushed from its primary
// hit, traced to completion.
void specular_listed(uint i) {
    ivec2 px;
    PrimaryHit p;
    if (!work_item(i, px) || !specular_root(px, p)) return;
    // A chain the selection started is traced whole.
    g_effects = EFFECT_ALL;
    imageStore(specular_out, px, vec4(trace_branches(), 1.0));
    budget_count_rays(p.instance);
}
