// Geometry and material at a ray hit, read from the one shared vertex/index copy.
#ifndef HIT_GLSL
#define HIT_GLSL
#include "scene.glsl"
#ifndef MAT_SAMPLE
// Rays have no derivatives: the ray cone sets the level (scene.glsl).
#define MAT_SAMPLE(index, xf, uv, fallback) sample_tex_cone(index, xf, uv, fallback)
#endif
#include "material.glsl"
#include "offset.glsl"
#include "primary_hit.glsl"

struct RayHit {
    uint instance;
    uint primitive;
    vec2 bary;  // weights of vertices 1 and 2
    float t;
};

struct HitVertices {
    Vertex v0, v1, v2;
};

HitVertices hit_vertices(Instance inst, uint primitive) {
    uint base = inst.first_index + 3u * primitive;
    HitVertices hv;
    hv.v0 = vertices[inst.vertex_offset + indices[base]];
    hv.v1 = vertices[inst.vertex_offset + indices[base + 1u]];
    hv.v2 = vertices[inst.vertex_offset + indices[base + 2u]];
    return hv;
}

vec3 bary3(vec2 b) {
    return vec3(1.0 - b.x - b.y, b.x, b.y);
}

vec2 hit_uv(HitVertices hv, vec2 b) {
    vec3 w = bary3(b);
    return hv.v0.uv * w.x + hv.v1.uv * w.y + hv.v2.uv * w.z;
}

// The rasterizer's uv gradients at pixel `px` (neighbouring camera rays on the triangle's plane), so
// pure-RT camera rays filter textures and alpha cut-outs exactly like the G-buffer pass.
void camera_uv_gradients(uint instance, uint primitive, ivec2 px, out vec2 dx, out vec2 dy) {
    TriangleWorld t = triangle_world(instance, primitive);
    HitVertices hv = hit_vertices(instances[instance], primitive);
    vec2 c = vec2(px) + 0.5;
    vec2 b0 = plane_barycentrics_unclamped(t, frame.camera_pos, camera_ray_dir(c));
    vec2 bx = plane_barycentrics_unclamped(t, frame.camera_pos, camera_ray_dir(c + vec2(1.0, 0.0)));
    vec2 by = plane_barycentrics_unclamped(t, frame.camera_pos, camera_ray_dir(c + vec2(0.0, 1.0)));
    vec2 uv0 = hit_uv(hv, b0);
    dx = hit_uv(hv, bx) - uv0;
    dy = hit_uv(hv, by) - uv0;
}

// Pure-RT camera rays alpha-test filtered alpha like the raster.
bool g_camera_ray = false;
ivec2 g_camera_pixel = ivec2(0);
// Reflection/refraction rays alpha-test at the mip their shading picks (a cut-out in a mirror does
// not sparkle); zero cone (shadow rays): the finest level.
vec2 g_alpha_cone = vec2(0.0);
vec3 g_alpha_dir = vec3(0.0, 0.0, 1.0);

// Half the log2 uv/world area ratio plus log2 of cone width over the cosine; no cone: finest level.
float cone_lod(HitVertices hv, vec3 e1, vec3 e2, vec3 gn, vec3 ray_d, float cone_width) {
    vec2 t1 = hv.v1.uv - hv.v0.uv;
    vec2 t2 = hv.v2.uv - hv.v0.uv;
    float uv_area = abs(t1.x * t2.y - t2.x * t1.y);
    float world_area = length(cross(e1, e2));
    if (!(uv_area > 0.0 && world_area > 0.0 && cone_width > 0.0)) return -64.0;
    float cosine = max(abs(dot(gn, ray_d)), 1e-3);
    return 0.5 * log2(uv_area / world_area) + log2(cone_width / cosine);
}

float hit_alpha(uint instance, uint primitive, vec2 b, float t) {
    Instance inst = instances[instance];
    Material m = materials[inst.material];
    HitVertices hv = hit_vertices(inst, primitive);
    vec2 uv = hit_uv(hv, b);
    if (m.tex_base_color < 0) return m.base_color.a;
    if (g_camera_ray) {
        vec2 dx, dy;
        camera_uv_gradients(instance, primitive, g_camera_pixel, dx, dy);
        return m.base_color.a * sample_tex_grad(m.tex_base_color, m.uv_base_color, uv, dx, dy, vec4(1.0)).a;
    }
    float lod = 0.0;
    if (g_alpha_cone != vec2(0.0)) {
        vec3 p0 = (inst.world * vec4(hv.v0.position, 1.0)).xyz;
        vec3 e1 = mat3(inst.world) * (hv.v1.position - hv.v0.position);
        vec3 e2 = mat3(inst.world) * (hv.v2.position - hv.v0.position);
        vec3 gn = cross(e1, e2);
        gn = dot(gn, gn) > 0.0 ? normalize(gn) : vec3(0.0, 1.0, 0.0);
        float width = g_alpha_cone.x + g_alpha_cone.y * t;
        lod = max(texel_lod(m.tex_base_color, m.uv_base_color, cone_lod(hv, e1, e2, gn, g_alpha_dir, width)), 0.0);
    }
    return m.base_color.a * sample_tex_lod(m.tex_base_color, m.uv_base_color, uv, lod, vec4(1.0)).a;
}

bool hit_alpha_passes(uint instance, uint primitive, vec2 b, float t) {
    Material m = materials[instances[instance].material];
    if (m.alpha_mode == ALPHA_OPAQUE) return true;
    return hit_alpha(instance, primitive, b, t) >= m.alpha_cutoff;
}

// Shadow rays see glass as opaque, like the path tracer's (FRAME_OPAQUE_OCCLUDERS does so for the
// whole frame): `terms` sets it around rays compared with the truth; RT any-hit reads the payload.
bool g_opaque_occluders = false;

// 0 for opaque (and glass when occluders are opaque), transmission-weighted base colour for glass,
// 1 where an alpha mask cuts the surface away.
vec3 occluder_transmittance(uint instance, uint primitive, vec2 b) {
    Instance inst = instances[instance];
    Material m = materials[inst.material];
    vec2 uv = hit_uv(hit_vertices(inst, primitive), b);
    vec4 base = m.base_color * sample_tex_lod(m.tex_base_color, m.uv_base_color, uv, 0.0, vec4(1.0));
    if (m.alpha_mode != ALPHA_OPAQUE && base.a < m.alpha_cutoff) return vec3(1.0);
    // Glass bends light, so a straight ray through it carries none (it arrives along refracted paths).
    if ((frame.flags & FRAME_OPAQUE_OCCLUDERS) != 0u || g_opaque_occluders) return vec3(0.0);
    float tr = clamp(m.transmission * sample_tex_lod(m.tex_transmission, m.uv_transmission, uv, 0.0, vec4(1.0)).r,
                     0.0, 1.0);
    return base.rgb * tr;
}

// Beer-Lambert through the medium behind the back face hit; closed meshes assumed (KHR_materials_volume).
vec3 volume_transmittance(RayHit h) {
    return exp(-materials[instances[h.instance].material].volume_sigma * h.t);
}

// The interpolated vertex normal (world, unit, on `geo_normal`'s side) and tangent at weights `w`.
void vertex_frame(Instance inst, HitVertices hv, vec3 w, vec3 geo_normal, out vec3 n, out vec4 tangent) {
    n = hv.v0.normal * w.x + hv.v1.normal * w.y + hv.v2.normal * w.z;
    n = mat3(inst.normal_matrix) * n;
    n = dot(n, n) > 1e-20 ? normalize(n) : geo_normal;
    if (dot(n, geo_normal) < 0.0) n = -n;
    vec4 t4 = hv.v0.tangent * w.x + hv.v1.tangent * w.y + hv.v2.tangent * w.z;
    tangent = vec4(mat3(inst.world) * t4.xyz, hv.v0.tangent.w);
}

// `geo_normal`: unit world-space geometric normal on the ray's side; the shading normal follows.
// `cone_width`: the ray cone's width at the hit (texture LOD).
Surface hit_surface(RayHit h, vec3 ray_o, vec3 ray_d, float cone_width, out vec3 geo_normal, out bool back_face) {
    Instance inst = instances[h.instance];
    Material m = materials[inst.material];
    HitVertices hv = hit_vertices(inst, h.primitive);
    vec3 w = bary3(h.bary);
    vec3 p0 = (inst.world * vec4(hv.v0.position, 1.0)).xyz;
    vec3 p1 = (inst.world * vec4(hv.v1.position, 1.0)).xyz;
    vec3 p2 = (inst.world * vec4(hv.v2.position, 1.0)).xyz;
    Surface s;
    // From the triangle, not o + t*d, so the point lies on the surface.
    s.position = p0 * w.x + p1 * w.y + p2 * w.z;
    s.extent = triangle_extent(p0, p1, p2);
    vec3 gn = cross(p1 - p0, p2 - p0);
    gn = dot(gn, gn) > 0.0 ? normalize(gn) : vec3(0.0, 1.0, 0.0);
    back_face = dot(gn, ray_d) > 0.0;
    geo_normal = back_face ? -gn : gn;
    vec3 n;
    vec4 tangent;
    vertex_frame(inst, hv, w, geo_normal, n, tangent);
    vec2 uv = hv.v0.uv * w.x + hv.v1.uv * w.y + hv.v2.uv * w.z;
    g_hit_lod = cone_lod(hv, p1 - p0, p2 - p0, gn, ray_d, cone_width);
    float alpha;
    material_eval(m, uv, s, alpha);
    s.normal = apply_normal_map(m, uv, n, tangent);
    s.clearcoat_normal = s.clearcoat > 0.0 ? coat_normal(m, uv, n, tangent) : s.normal;
    return s;
}

#endif
