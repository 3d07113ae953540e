//! Memory accounting shared by every structure (docs/design.md §3, §8: `memory.components`, N_c, N_p).

use serde::Serialize;

/// Bytes by named component, plus node and pointer counts in each paper's own definition.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct MemoryReport {
    /// `(component, bytes)` in a stable order, e.g. `("nodes", 1234)`.
    pub components: Vec<(String, u64)>,
    /// N_c: nodes (BVH, octrees) or cells over all levels (grids).
    pub nodes: u64,
    /// N_p: pointers (octrees) or triangle references (grids, BVH leaves).
    pub pointers: u64,
}

impl MemoryReport {
    pub fn new(nodes: u64, pointers: u64) -> Self {
        Self { components: Vec::new(), nodes, pointers }
    }

    pub fn with(mut self, component: &str, bytes: u64) -> Self {
        self.components.push((component.to_string(), bytes));
        self
    }

    pub fn total_bytes(&self) -> u64 {
        self.components.iter().map(|(_, b)| b).sum()
    }
}

/// Bytes per voxel of each component, in the report's order: a voxel structure's
/// `bytes_per_voxel_by_component`, so memory per voxel compares across structures part by part.
pub fn per_voxel(memory: &MemoryReport, voxels: u64) -> serde_json::Map<String, serde_json::Value> {
    let voxels = voxels.max(1) as f64;
    memory.components.iter().map(|(name, bytes)| (name.clone(), serde_json::json!(*bytes as f64 / voxels))).collect()
}
