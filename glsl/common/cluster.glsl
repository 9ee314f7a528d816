// The G-buffer's clusters and their indirect draws (gpu/clusters.rs,
// render/occlusion.rs): set 1 of the cull pass.
#ifndef CLUSTER_GLSL
#define CLUSTER_GLSL
#include "types.glsl"

struct Cluster {
    vec3 lo;  // object-space box of the cluster's triangles
    uint instance;
    vec3 hi;
};

// VkDrawIndirectCommand (the raster draws clusters like whole draws: not
// indexed, common/gbuffer_draw.glsl); the cull pass writes instance_count only.
struct DrawCommand {
    uint vertex_count;
    uint instance_count;
    uint first_vertex;
    uint first_instance;
};

layout(set = SET_PASS, binding = OCC_CLUSTERS, scalar) readonly buffer Clusters { Cluster clusters[]; };
#endif
