//! The scene's GPU memory by category ([`GpuScene::memory`](super::GpuScene::memory)): what the
//! upload log and the scale measurements report.

/// Bytes in use by category.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneMemory {
    /// The vertex buffer (the skinned instances' deformed copies included).
    pub vertices: u64,
    pub indices: u64,
    /// Material textures with their mips.
    pub textures: u64,
    /// The environment map, its GGX-prefiltered copy, the split-sum table and the sampling table.
    pub environment: u64,
    pub prt: u64,
    pub shadow_maps: u64,
    /// Materials, instances, lights and the per-frame buffers.
    pub other: u64,
}

impl SceneMemory {
    pub fn total(&self) -> u64 {
        self.vertices
            + self.indices
            + self.textures
            + self.environment
            + self.prt
            + self.shadow_maps
            + self.other
    }

    /// Vertex and index bytes per triangle.
    pub fn geometry_per_triangle(&self, triangles: usize) -> f64 {
        (self.vertices + self.indices) as f64 / triangles.max(1) as f64
    }

    /// The log line: each category in MiB, the geometry's bytes per triangle.
    pub fn describe(&self, triangles: usize) -> String {
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        format!(
            "scene GPU memory in use: {:.1} MiB = vertices {:.1} + indices {:.1} + textures {:.1} + \
             environment {:.1} + PRT {:.1} + shadow maps {:.1} + other {:.1}; geometry {:.1} B per triangle",
            mib(self.total()),
            mib(self.vertices),
            mib(self.indices),
            mib(self.textures),
            mib(self.environment),
            mib(self.prt),
            mib(self.shadow_maps),
            mib(self.other),
            self.geometry_per_triangle(triangles)
        )
    }
}
