// The primary hit as every pass after `gbuffer` / `primary` sees it: both modes write the same
// G-buffer targets (GB_*), and the exact hit point is rebuilt by intersecting the camera ray with the
// stored triangle. 24 bytes a pixel with depth: albedo rgba8, octahedral normal r32ui, metallic/
// roughness/transmission rgba8, hit rg32ui. Emission is not stored: `composite` looks it up.
#ifndef GBUFFER_READ_GLSL
#define GBUFFER_READ_GLSL
#include "scene.glsl"
#include "brdf.glsl"
#include "primary_hit.glsl"
#include "hit.glsl"
#include "gbuffer_pack.glsl"
#include "offset.glsl"
#include "srgb.glsl"

layout(set = SET_PASS, binding = GB_ALBEDO) uniform sampler2D gb_albedo;
layout(set = SET_PASS, binding = GB_NORMAL) uniform usampler2D gb_normal;
layout(set = SET_PASS, binding = GB_MATERIAL) uniform sampler2D gb_material;
layout(set = SET_PASS, binding = GB_HIT) uniform usampler2D gb_hit;

struct PrimaryHit {
    Surface s;
    vec3 dir;       // camera ray direction through the pixel centre
    vec3 gn;        // unit geometric normal on the viewer's side
    bool back_face;
    uint instance;
    uint primitive;  // triangle of the instance
    vec2 b;          // barycentrics (b1, b2) of the hit on it
};

// Texture filtered with the rasterizer's uv gradients, as the G-buffer pass sampled it.
vec3 primary_emissive(ivec2 px, uint instance, uint primitive, vec2 b) {
    Material m = materials[instances[instance].material];
    if (m.emissive == vec3(0.0) || m.tex_emissive < 0) return m.emissive;
    vec2 uv = hit_uv(hit_vertices(instances[instance], primitive), b);
    vec2 dx, dy;
    camera_uv_gradients(instance, primitive, px, dx, dy);
    return m.emissive * sample_tex_grad(m.tex_emissive, m.uv_emissive, uv, dx, dy, vec4(1.0)).rgb;
}

// KHR_materials_specular at the pixel's hit. The G-buffer does not store it: the factors come from
// the material, and only materials with its textures sample them (filtered as the G-buffer pass would).
void primary_specular(ivec2 px, uvec2 hit, Material m, inout Surface s) {
    s.specular = m.specular;
    s.specular_color = m.specular_color;
    if (m.tex_specular < 0 && m.tex_specular_color < 0) return;
    uint instance = hit.x - 1u;
    vec2 b = plane_barycentrics(triangle_world(instance, hit.y), frame.camera_pos, camera_ray_dir(vec2(px) + 0.5));
    vec2 uv = hit_uv(hit_vertices(instances[instance], hit.y), b);
    vec2 dx, dy;
    camera_uv_gradients(instance, hit.y, px, dx, dy);
    s.specular = clamp(s.specular * sample_tex_grad(m.tex_specular, m.uv_specular, uv, dx, dy, vec4(1.0)).a, 0.0, 1.0);
    s.specular_color *= sample_tex_grad(m.tex_specular_color, m.uv_specular_color, uv, dx, dy, vec4(1.0)).rgb;
}

// KHR_materials_clearcoat at the pixel's hit, not stored either: factors from the material, textures
// filtered as the G-buffer pass would, the coat's normal rebuilt from the triangle's vertices (its own
// map filtered at the pixel's ray cone). Without a coat its fields stay at "none".
void primary_clearcoat(ivec2 px, uvec2 hit, Material m, inout Surface s) {
    s.clearcoat = m.clearcoat;
    s.clearcoat_roughness = m.clearcoat_roughness;
    s.clearcoat_normal = vec3(0.0, 0.0, 1.0);
    if (m.clearcoat <= 0.0) return;
    uint instance = hit.x - 1u;
    Instance inst = instances[instance];
    TriangleWorld tri = triangle_world(instance, hit.y);
    vec3 dir = camera_ray_dir(vec2(px) + 0.5);
    vec2 b = plane_barycentrics(tri, frame.camera_pos, dir);
    HitVertices hv = hit_vertices(inst, hit.y);
    vec2 uv = hit_uv(hv, b);
    if (m.tex_clearcoat >= 0 || m.tex_clearcoat_roughness >= 0) {
        vec2 dx, dy;
        camera_uv_gradients(instance, hit.y, px, dx, dy);
        s.clearcoat = clamp(s.clearcoat * sample_tex_grad(m.tex_clearcoat, m.uv_clearcoat, uv, dx, dy, vec4(1.0)).r, 0.0, 1.0);
        s.clearcoat_roughness = clamp(
            s.clearcoat_roughness * sample_tex_grad(m.tex_clearcoat_roughness, m.uv_clearcoat_roughness, uv, dx, dy, vec4(1.0)).g,
            0.0, 1.0);
    }
    vec3 e1 = tri.p1 - tri.p0, e2 = tri.p2 - tri.p0;
    vec3 gn = cross(e1, e2);
    gn = dot(gn, gn) > 0.0 ? normalize(gn) : -dir;
    if (dot(gn, dir) > 0.0) gn = -gn;
    vec3 n;
    vec4 tangent;
    vertex_frame(inst, hv, bary3(b), gn, n, tangent);
    if (m.tex_clearcoat_normal >= 0) {
        float width = pixel_spread_angle() * distance(frame.camera_pos, interpolate(tri, b));
        g_hit_lod = cone_lod(hv, e1, e2, gn, dir, width);
        n = coat_normal(m, uv, n, tangent);
    }
    s.clearcoat_normal = n;
}

// Material terms only, enough to decide which rays the hit spawns. False on a miss (hit id 0).
bool read_primary_material(ivec2 px, out uvec2 hit, out Surface s) {
    hit = texelFetch(gb_hit, px, 0).xy;
    if (hit.x == 0u) return false;
    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 mat = texelFetch(gb_material, px, 0);
    s.base_color = srgb_decode(albedo.rgb);
    s.occlusion = albedo.a;
    s.metallic = mat.r;
    s.roughness = mat.g;
    s.transmission = mat.b;
    Material m = materials[instances[hit.x - 1u].material];
    s.ior = m.ior;
    primary_specular(px, hit, m, s);
    primary_clearcoat(px, hit, m, s);
    // Only `composite` adds emission, so the tracing passes skip its texture lookup.
    s.emissive = vec3(0.0);
    return true;
}

// False on a miss.
bool read_primary(ivec2 px, out PrimaryHit p) {
    p.dir = camera_ray_dir(vec2(px) + 0.5);
    uvec2 hit;
    if (!read_primary_material(px, hit, p.s)) return false;
    p.instance = hit.x - 1u;
    TriangleWorld tri = triangle_world(p.instance, hit.y);
    vec2 b = plane_barycentrics(tri, frame.camera_pos, p.dir);
    p.primitive = hit.y;
    p.b = b;
    p.s.position = interpolate(tri, b);
    p.s.extent = triangle_extent(tri.p0, tri.p1, tri.p2);
    vec3 tn = cross(tri.p1 - tri.p0, tri.p2 - tri.p0);
    tn = dot(tn, tn) > 0.0 ? normalize(tn) : -p.dir;
    p.back_face = dot(tn, p.dir) > 0.0;
    p.gn = p.back_face ? -tn : tn;
    p.s.normal = oct_decode(texelFetch(gb_normal, px, 0).x);
    return true;
}

bool outside_frame(ivec2 px) {
    return any(greaterThanEqual(uvec2(px), frame.resolution));
}

#endif
