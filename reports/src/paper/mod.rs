//! Paper results reproduced from a run (docs/design.md §9): Fig. 1, Fig. 2 and Table 1 of seed 002
//! (Li & Wang 2011), each in the paper's layout, with fitted growth exponents; seed 001's SVDAG
//! tables ([`svdag_tables`]); ESVO at scale (blocks, bytes, build peak, LOD; issue 18);
//! and, for any run with ESVO cases, its bytes per voxel beside seed 000's budget. The papers'
//! claims are marked held or not held.

//!
//! One file per reproduced result, above the claims (`crate::claims`) and the helpers they share:
//! [`org_scaling`] (seed 002 Fig. 1 and Fig. 2), [`org_table1`] (Table 1), [`svdag_tables`] (seed
//! 001 Tables 1–3, Fig. 13), [`svdag_shadow`] (Table 4), [`svdag_temporal`] (Tables 5–6), [`esvo`]
//! (seed 000 §5.6 and §6.2, ESVO at scale), [`voxel_grids`] (grid or octree on the same voxels),
//! [`volumes`] (seed 003's volumes: empty space skipped per structure), [`ooc`] (issue 42: volumes
//! larger than memory through a brick cache and page tables), [`simd_parity`] (issue 30:
//! every family beside Embree, SIMD and scalar), [`cell_order`] (issue 43: Morton against
//! row-major cell tables);
//! `grid_builds` is what the grid reproductions share.

pub mod cell_order;
pub mod esvo;
mod grid_builds;
pub mod ooc;
pub mod org_scaling;
pub mod org_table1;
pub mod simd_parity;
pub mod svdag_shadow;
pub mod svdag_tables;
pub mod svdag_temporal;
#[cfg(test)]
mod tests;
pub mod volumes;
pub mod voxel_grids;

use crate::claims::Sheet;

/// The distinct names of `names`, each where it first appears.
fn first_seen<'a>(names: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for name in names {
        if !out.contains(&name) {
            out.push(name);
        }
    }
    out
}
use crate::schema::Results;

use esvo::{esvo_beam, esvo_budget, esvo_scale};
use org_scaling::{Scaling, scaling};
use org_table1::table1;

/// The reproduction section for the run's preset (empty for other presets), with the claims it
/// checks.
pub fn section(results: &Results) -> Sheet {
    let mut out = match results.settings.preset.as_str() {
        "org-fig1" => scaling(results, Scaling::FIG1),
        "org-fig2" => scaling(results, Scaling::FIG2),
        "org-table1" => table1(results),
        "svdag-tables" => svdag_tables::section(results),
        "esvo-scale" => esvo_scale(results),
        "simd-parity" => simd_parity::section(results),
        _ => Sheet::default(),
    };
    // Tables 4–6 wherever a run has shadow or temporal SVDAG cases, the beam wherever ESVO ran
    // with and without it.
    out.append(svdag_shadow::section(results));
    out.append(svdag_temporal::section(results));
    out.append(esvo_beam(results));
    out.append(esvo_budget(results));
    // Grid or octree on the same voxels wherever a run has a hierarchical voxel grid.
    out.append(voxel_grids::section(results));
    // Morton against row-major wherever a run has a structure's cells in both orders.
    out.append(cell_order::section(results));
    // Seed 003's volumes wherever a run has volume cases.
    out.append(volumes::section(results));
    // Seed 003's volumes larger than memory wherever a run has out-of-core cases.
    out.append(ooc::section(results));
    out
}
