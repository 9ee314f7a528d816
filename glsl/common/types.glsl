// Host/shader shared structs. Mirrored by src/render/gpu_types.rs with
// compile-time size asserts; all blocks use scalar layout.
#ifndef TYPES_GLSL
#define TYPES_GLSL

#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_nonuniform_qualifier : require

struct Vertex {
    vec3 position;
    vec3 normal;
    vec2 uv;
    vec4 tangent;
};

#define ALPHA_OPAQUE 0u
#define ALPHA_MASK 1u
#define ALPHA_BLEND 2u

#define MAT_DOUBLE_SIDED 1u
#define MAT_CASTS_SHADOWS 2u

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
    uint pad0;
    uint pad1;
};

#define INST_CASTS_SHADOWS 1u

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

#define LIGHT_DIRECTIONAL 0u
#define LIGHT_POINT 1u
#define LIGHT_SPOT 2u
#define LIGHT_CASTS_SHADOWS 1u

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

#define DEBUG_NONE 0u
#define DEBUG_ALBEDO 1u
#define DEBUG_NORMAL 2u
#define DEBUG_DEPTH 3u
#define DEBUG_MATERIAL 4u
#define DEBUG_OBJECT 5u

struct Frame {
    mat4 view;
    mat4 proj;
    mat4 view_proj;
    mat4 inv_view_proj;
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
};

#endif
