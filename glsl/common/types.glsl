// Host/shader shared structs. Mirrored by src/gpu/types.rs with
// compile-time size asserts (strides: generated/shared.glsl); all blocks use scalar layout.
#ifndef TYPES_GLSL
#define TYPES_GLSL

#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_nonuniform_qualifier : require
#include "generated/shared.glsl"

struct Vertex {
    vec3 position;
    vec3 normal;
    vec2 uv;
    vec4 tangent;
};

// An affine map of texture coordinates: uv' = (dot(row0, (uv, 1)), dot(row1, (uv, 1))).
struct UvTransform {
    vec3 row0;
    vec3 row1;
};

struct Material {
    vec4 base_color;
    vec3 emissive;
    float metallic;
    float roughness;
    float normal_scale;
    float occlusion_strength;
    float alpha_cutoff;
    float transmission;
    float ior;
    uint alpha_mode;
    uint flags;
    int tex_base_color;
    int tex_metallic_roughness;
    int tex_normal;
    int tex_occlusion;
    int tex_emissive;
    int tex_transmission;
    // Beer-Lambert attenuation per world unit inside the closed mesh
    // (KHR_materials_volume; 0: clear).
    vec3 volume_sigma;
    // KHR_materials_specular: the dielectric reflection's weight (x texture A) and the F0 colour's
    // texture (RGB; its factor is specular_color below).
    float specular;
    int tex_specular;
    int tex_specular_color;
    // KHR_texture_transform of each tex_* reference above, in their order.
    UvTransform uv_base_color;
    UvTransform uv_metallic_roughness;
    UvTransform uv_normal;
    UvTransform uv_occlusion;
    UvTransform uv_emissive;
    UvTransform uv_transmission;
    UvTransform uv_specular;
    UvTransform uv_specular_color;
    // Multiplies the IOR's F0 (clamped to 1 after).
    vec3 specular_color;
    uint pad0;
    // KHR_materials_clearcoat: the coat's weight (x texture R), roughness (x texture G) and normal
    // map (scale, texture; none: the interpolated vertex normal), then those references' transforms.
    float clearcoat;
    float clearcoat_roughness;
    float clearcoat_normal_scale;
    int tex_clearcoat;
    int tex_clearcoat_roughness;
    int tex_clearcoat_normal;
    UvTransform uv_clearcoat;
    UvTransform uv_clearcoat_roughness;
    UvTransform uv_clearcoat_normal;
};

struct Instance {
    mat4 world;
    mat4 normal_matrix;
    uint material;
    uint first_index;
    uint vertex_offset;
    uint object_id;
    uint index_count;
    uint flags;
    uint pad0;
    uint pad1;
};

struct Light {
    vec3 position;
    uint type;
    vec3 direction;  // direction the light travels
    float range;     // <= 0: infinite
    vec3 radiance;   // colour * intensity
    float spot_scale;
    float spot_offset;
    uint flags;
    float pad0;
    float pad1;
};

struct Frame {
    mat4 view;
    mat4 proj;
    mat4 view_proj;
    mat4 inv_view_proj;
    // The previous frame's (FRAME_GLOSSY_HISTORY: a history to reproject into exists).
    mat4 prev_view_proj;
    vec3 prev_camera_pos;
    // The integrator's recursion limits (uniforms, not specialization constants: changing them compiles
    // nothing): branches deeper than max_depth or weighing under min_weight are not traced.
    uint max_depth;
    vec3 camera_pos;
    uint light_count;
    vec3 env_color;
    float env_intensity;
    vec3 env_ambient;
    float env_rotation;
    uvec2 resolution;
    uint has_env_map;
    uint debug_view;
    float exposure;
    uint frame_index;
    uint flags;
    float znear;
    // render/tone.rs: white <= 0 means the frame's brightest pixel, adapt step <= 0 converges at once;
    // speeds in EV per second.
    uint tonemap;
    uint auto_exposure;
    float key;
    float white;
    float adapt_dt;
    float hist_low;
    float hist_high;
    float speed_brighten;
    float speed_darken;
    // Accumulating passes (`reference`, `path`, `terms`): accum_frame 0 starts over and seeds the RNG;
    // accum_bounces is the longest path, or `terms`' TERM_* selection; path_clamp <= 0: unbiased.
    uint accum_frame;
    uint accum_bounces;
    float path_clamp;
    float min_weight;
    uint pad_limits[3];
    // The environment's SH irradiance E_lm (rgb), with FRAME_AMBIENT_SH.
    vec4 sh_irradiance[SH_IRRADIANCE_COEFFS];
    // The environment's SH radiance L_lm (rgb), with FRAME_AMBIENT_PRT.
    vec4 sh_radiance[SH_PRT_MAX_COEFFS];
};

#endif
