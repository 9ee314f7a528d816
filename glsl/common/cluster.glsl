// The G-buffer's clusters and their indirect draws (gpu/clusters.rs,
// render/occlusion.rs): set 1 of the cull pass and the cluster raster.
#ifndef CLUSTER_GLSL
#define CLUSTER_GLSL
#include "types.glsl"

struct Cluster {
    vec3 lo;  // object-space box of the cluster's triangles
    uint instance;
    vec3 hi;
    uint first_primitive;  // within its draw: added to gl_PrimitiveID
};

// VkDrawIndexedIndirectCommand; the cull pass writes instance_count only.
struct DrawCommand {
    uint index_count;
    uint instance_count;
    uint first_index;
    int vertex_offset;
    uint first_instance;  // the cluster's index
};

layout(set = SET_PASS, binding = OCC_CLUSTERS, scalar) readonly buffer Clusters { Cluster clusters[]; };
#endif
