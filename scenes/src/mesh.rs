//! An indexed triangle mesh (DESIGN.md §3).

use glam::{Mat4, Vec3};

use crate::error::{Location, SceneError};
use crate::geom::Aabb;

/// Positions, triangle indices and optional per-vertex normals and colours.
///
/// Degenerate triangles (zero area, or repeated indices) are kept: structures must cope with
/// them, and [`Mesh::degenerate_count`] reports how many there are.
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

    /// Triangles with zero area (including repeated indices). They are kept, never hit.
    pub fn degenerate_count(&self) -> usize {
        (0..self.indices.len())
            .filter(|&i| {
                let [a, b, c] = self.triangle(i);
                (b - a).cross(c - a) == Vec3::ZERO
            })
            .count()
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
