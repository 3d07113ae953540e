//! An indexed triangle mesh (docs/design.md §3).

use foldhash::fast::FixedState;
use glam::{DVec3, Mat4, Vec3};
use hashbrown::HashSet;

use crate::error::{Location, SceneError};
use crate::geom::Aabb;

/// Triangles dropped from a scene before any build ([`Mesh::drop_unusable`]), reported in the
/// results and the log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Dropped {
    /// Zero area ([`Mesh::is_degenerate`]).
    pub degenerate: u64,
    /// The same corners as an earlier triangle: a duplicated face.
    pub duplicate: u64,
}

impl Dropped {
    pub fn total(&self) -> u64 {
        self.degenerate + self.duplicate
    }
}

/// Positions, triangle indices and optional per-vertex normals and colours.
///
/// A mesh keeps what its file holds, degenerate and duplicated triangles included
/// ([`Mesh::degenerate_count`]); a scene drops them before anything is built from it
/// ([`Mesh::drop_unusable`], called by [`crate::load_scene`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub name: String,
    /// Where the data came from (file header line, generator and seed).
    pub provenance: String,
    pub positions: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
    pub normals: Option<Vec<Vec3>>,
    pub colors: Option<Vec<Vec3>>,
}

impl Mesh {
    pub fn new(name: impl Into<String>, provenance: impl Into<String>) -> Self {
        Self { name: name.into(), provenance: provenance.into(), ..Self::default() }
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The three corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    pub fn bounds(&self) -> Aabb {
        // Only referenced vertices count: an unused outlier vertex must not stretch the scene.
        Aabb::from_points(self.indices.iter().flatten().map(|&i| self.positions[i as usize]))
    }

    /// Triangles with zero area ([`Mesh::is_degenerate`]).
    pub fn degenerate_count(&self) -> usize {
        (0..self.indices.len()).filter(|&i| self.is_degenerate(i)).count()
    }

    /// True when triangle `i` has zero area in double precision: a repeated index, or corners
    /// that coincide or lie on one line. (A sliver whose area underflows single precision, a
    /// 10⁻³⁰-sized triangle, is not degenerate: it is kept, and the structures cope with it.)
    pub fn is_degenerate(&self, i: usize) -> bool {
        let [a, b, c] = self.triangle(i).map(|p| p.as_dvec3());
        (b - a).cross(c - a) == DVec3::ZERO
    }

    /// Drops degenerate triangles and duplicated faces (the same three corners as an earlier
    /// triangle, in any order or winding; the earlier one is kept): neither can change what a ray
    /// hits, yet every structure would pay for them (issue 31: 200,000 copies of one face made
    /// the reference BVH quadratic). Returns what was dropped and, per original triangle, whether
    /// it was kept. Vertices are left as they are.
    pub fn drop_unusable(&mut self) -> (Dropped, Vec<bool>) {
        let mut dropped = Dropped::default();
        let mut seen: HashSet<[[u32; 3]; 3], FixedState> =
            HashSet::with_capacity_and_hasher(self.indices.len(), FixedState::default());
        let keep: Vec<bool> = (0..self.indices.len())
            .map(|i| {
                if self.is_degenerate(i) {
                    dropped.degenerate += 1;
                    return false;
                }
                // Corners as bits, sorted: any order and either winding give one key.
                let mut key = self.triangle(i).map(|p| p.to_array().map(f32::to_bits));
                key.sort_unstable();
                let new = seen.insert(key);
                dropped.duplicate += u64::from(!new);
                new
            })
            .collect();
        if dropped.total() > 0 {
            let mut kept = keep.iter();
            self.indices.retain(|_| *kept.next().expect("one flag per triangle"));
        }
        (dropped, keep)
    }

    /// Adds a vertex and returns its index.
    pub fn push_vertex(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    /// Appends `other` transformed by `transform`. Attributes present on only one side are
    /// filled (normals with the transformed geometric default of zero, colours with white) so
    /// that attribute arrays always match the position count.
    pub fn append(&mut self, other: &Mesh, transform: Mat4) {
        let base = self.positions.len() as u32;
        let had_vertices = !self.positions.is_empty();
        let normal_matrix = transform.inverse().transpose();
        match (&mut self.normals, &other.normals) {
            (Some(n), Some(o)) => n.extend(o.iter().map(|&v| normal_matrix.transform_vector3(v).normalize_or_zero())),
            (Some(n), None) => n.extend(std::iter::repeat_n(Vec3::ZERO, other.positions.len())),
            (None, Some(o)) => {
                let mut n = vec![Vec3::ZERO; self.positions.len()];
                n.extend(o.iter().map(|&v| normal_matrix.transform_vector3(v).normalize_or_zero()));
                self.normals = Some(n);
            }
            (None, None) => {}
        }
        match (&mut self.colors, &other.colors) {
            (Some(c), Some(o)) => c.extend_from_slice(o),
            (Some(c), None) => c.extend(std::iter::repeat_n(Vec3::ONE, other.positions.len())),
            (None, Some(o)) if had_vertices => {
                let mut c = vec![Vec3::ONE; self.positions.len()];
                c.extend_from_slice(o);
                self.colors = Some(c);
            }
            (None, Some(o)) => self.colors = Some(o.clone()),
            (None, None) => {}
        }
        self.positions.extend(other.positions.iter().map(|&p| transform.transform_point3(p)));
        self.indices.extend(other.indices.iter().map(|t| t.map(|i| i + base)));
    }

    /// Checks the mesh contract: at least one triangle, finite coordinates, indices in range,
    /// attribute arrays matching the vertex count. `path` names the source in the error; the
    /// location is the element index (loaders with line numbers check earlier, in their own terms).
    pub fn validate(&self, path: &str) -> Result<(), SceneError> {
        if self.indices.is_empty() {
            return Err(SceneError::Empty {
                path: path.into(),
                detail: format!("mesh '{}' has no triangles", self.name),
            });
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(SceneError::NonFinite {
                path: path.into(),
                location: Location::Element(format!("mesh '{}' vertex {i}", self.name)),
                detail: format!("{:?}", self.positions[i]),
            });
        }
        if let Some(i) = self.positions.iter().position(|&p| !crate::geom::coordinate_in_range(p)) {
            return Err(SceneError::OutOfRange {
                path: path.into(),
                location: Location::Element(format!("mesh '{}' vertex {i}", self.name)),
                detail: format!("{:?}", self.positions[i]),
            });
        }
        let n = self.positions.len();
        for (t, tri) in self.indices.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(SceneError::IndexOutOfRange {
                    path: path.into(),
                    location: Location::Element(format!("mesh '{}' triangle {t}", self.name)),
                    index: i64::from(bad),
                    vertex_count: n,
                });
            }
        }
        for (what, len) in
            [("normals", self.normals.as_ref().map(Vec::len)), ("colors", self.colors.as_ref().map(Vec::len))]
        {
            if let Some(len) = len.filter(|&len| len != n) {
                return Err(SceneError::Malformed {
                    path: path.into(),
                    location: Location::Element(format!("mesh '{}' {what}", self.name)),
                    detail: format!("{len} {what} for {n} vertices"),
                });
            }
        }
        Ok(())
    }
}
