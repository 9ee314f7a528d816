// Pass `specular`: the reflection / refraction chain from the primary hit, secondary hits shaded in
// full. Two kernels (render/passes/compacted.rs): `specular_select` lists the pixels whose hit
// spawns a branch (common/work_list.glsl); the chain kernel traces them.
#include "../common/gbuffer_read.glsl"
#include "../common/integrator.glsl"
#include "../common/work_list.glsl"

layout(set = SET_PASS, binding = SPECULAR_OUT, rgba32f) uniform writeonly image2D specular_out;

// False where the pixel has no primary hit.
bool specular_root(ivec2 px, out PrimaryHit p) {
    if (!read_primary(px, p)) return false;
    vec3 v = -p.dir;
    float nv = face_viewer(p.s, v);
    g_effects = budget_effects(p.instance, px);
    float spread = pixel_spread_angle();
    Cone cone = Cone(spread * distance(frame.camera_pos, p.s.position), spread);
    push_branches(p.s, v, nv, p.gn, p.back_face, vec3(1.0), 0u, cone);
    return true;
}

// Decided from the G-buffer's material terms alone: the chain kernel reads the whole hit anyway (and
// writes zero where its branches fall under frame.min_weight).
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

void specular_listed(uint i) {
    ivec2 px;
    PrimaryHit p;
    if (!work_item(i, px) || !specular_root(px, p)) return;
    // A chain the selection started is traced whole.
    g_effects = EFFECT_ALL;
    imageStore(specular_out, px, vec4(trace_branches(), 1.0));
    budget_count_rays(p.instance);
}
