//! Closed, indexed building blocks shared by the procedural scenes: boxes, cube faces and surfaces
//! of revolution, plus a builder that records each object's triangle range.
//!
//! Every closed shape shares its vertices between triangles and winds its triangles
//! counter-clockwise seen from outside (`(b - a) × (c - a)` points out), so each undirected edge is
//! used by exactly two triangles, once in each direction — the two-manifold surfaces shadow SVDAG's
//! double depth maps rely on (docs/design.md §4.4).

use glam::{Mat4, UVec3, Vec2, Vec3};

use crate::camera::CameraSpec;
use crate::mesh::Mesh;
use crate::scene::{Object, Scene};

/// Collects a scene's merged mesh and its named objects in order, so the objects' triangle ranges
/// partition the mesh by construction.
pub(super) struct SceneBuilder {
    mesh: Mesh,
    objects: Vec<Object>,
}

impl SceneBuilder {
    pub(super) fn new() -> Self {
        Self { mesh: Mesh::default(), objects: Vec::new() }
    }

    /// The bounds of the triangles added so far.
    pub(super) fn bounds(&self) -> crate::geom::Aabb {
        self.mesh.bounds()
    }

    /// Adds the triangles `build` appends as one object.
    pub(super) fn object(&mut self, name: &str, closed: bool, build: impl FnOnce(&mut Mesh)) {
        let first = self.mesh.indices.len();
        build(&mut self.mesh);
        let count = self.mesh.indices.len() - first;
        self.objects.push(Object {
            name: name.to_string(),
            first_triangle: first as u32,
            triangle_count: count as u32,
            closed,
        });
    }

    pub(super) fn finish(
        self,
        name: &str,
        provenance: String,
        camera: Option<CameraSpec>,
        light: Option<Vec3>,
    ) -> Scene {
        let mut mesh = self.mesh;
        mesh.name = name.to_string();
        mesh.provenance = provenance.clone();
        Scene {
            name: name.to_string(),
            provenance,
            mesh,
            objects: self.objects,
            camera,
            light,
            animation: None,
            dropped: Default::default(),
        }
    }
}

/// The corners of the face of the unit cube `[0,1]³` on `axis` (0 = x, 1 = y, 2 = z) at 1
/// (`positive`) or 0, counter-clockwise seen from outside the cube.
pub(super) fn cube_face(axis: usize, positive: bool) -> [UVec3; 4] {
    // With u = axis+1, v = axis+2 (mod 3), e_u × e_v = e_axis, so 0, u, u+v, v turns
    // counter-clockwise about +axis.
    let unit = |a: usize| UVec3::from_array(std::array::from_fn(|i| u32::from(i == a % 3)));
    let (n, u, v) = (unit(axis), unit(axis + 1), unit(axis + 2));
    let base = if positive { n } else { UVec3::ZERO };
    let quad = [base, base + u, base + u + v, base + v];
    if positive { quad } else { [quad[0], quad[3], quad[2], quad[1]] }
}

/// Appends the two triangles of the quad `a b c d` (in winding order).
pub(super) fn push_quad(mesh: &mut Mesh, [a, b, c, d]: [u32; 4]) {
    mesh.indices.push([a, b, c]);
    mesh.indices.push([a, c, d]);
}

/// Appends the cube `[-0.5, 0.5]³` mapped by `transform` (which must keep handedness: rotations,
/// positive scales, translations): 8 shared vertices, 12 triangles. `inward` flips the winding,
/// for a room seen from inside.
pub(super) fn push_box(mesh: &mut Mesh, transform: Mat4, inward: bool) {
    let base = mesh.positions.len() as u32;
    for corner in 0..8u32 {
        let unit = Vec3::new((corner & 1) as f32, ((corner >> 1) & 1) as f32, ((corner >> 2) & 1) as f32);
        mesh.positions.push(transform.transform_point3(unit - 0.5));
    }
    for axis in 0..3 {
        for positive in [false, true] {
            let [a, b, c, d] = cube_face(axis, positive).map(|p| base + p.x + 2 * p.y + 4 * p.z);
            push_quad(mesh, if inward { [a, d, c, b] } else { [a, b, c, d] });
        }
    }
}

/// Appends a closed surface of revolution about +y, mapped by `transform` (handedness-preserving).
///
/// `profile` holds (radius, height) points walked so that the outside lies to the right when
/// going down the outer side (top to bottom for a sphere). A point with radius 0 becomes one pole
/// vertex joined to its neighbouring ring by a fan; other points become rings of `slices` vertices.
/// With `loop_profile` the last point joins the first (a torus); otherwise the surface is closed
/// only if the profile starts and ends at a pole (an open profile gives an open band, e.g. a bowl).
pub(super) fn push_lathe(mesh: &mut Mesh, profile: &[Vec2], slices: u32, loop_profile: bool, transform: Mat4) {
    enum Ring {
        Pole(u32),
        Ring(u32),
    }
    let rings: Vec<Ring> = profile
        .iter()
        .map(|p| {
            let first = mesh.positions.len() as u32;
            if p.x == 0.0 {
                mesh.positions.push(transform.transform_point3(Vec3::new(0.0, p.y, 0.0)));
                return Ring::Pole(first);
            }
            for j in 0..slices {
                let phi = std::f32::consts::TAU * j as f32 / slices as f32;
                let local = Vec3::new(p.x * phi.cos(), p.y, p.x * phi.sin());
                mesh.positions.push(transform.transform_point3(local));
            }
            Ring::Ring(first)
        })
        .collect();
    let pairs = rings.len().saturating_sub(1) + usize::from(loop_profile);
    for k in 0..pairs {
        let (upper, lower) = (&rings[k], &rings[(k + 1) % rings.len()]);
        for j in 0..slices {
            let next = (j + 1) % slices;
            match (upper, lower) {
                (Ring::Pole(p), Ring::Ring(r)) => mesh.indices.push([*p, r + next, r + j]),
                (Ring::Ring(r), Ring::Pole(p)) => mesh.indices.push([*p, r + j, r + next]),
                (Ring::Ring(a), Ring::Ring(b)) => push_quad(mesh, [a + j, a + next, b + next, b + j]),
                (Ring::Pole(_), Ring::Pole(_)) => {}
            }
        }
    }
}

/// A UV sphere of radius 1 about the origin as a lathe profile (`stacks` ≥ 2 bands, poles included).
pub(super) fn sphere_profile(stacks: u32) -> Vec<Vec2> {
    (0..=stacks)
        .map(|i| {
            let theta = std::f32::consts::PI * i as f32 / stacks as f32;
            let radius = if i == 0 || i == stacks { 0.0 } else { theta.sin() };
            Vec2::new(radius, theta.cos())
        })
        .collect()
}

/// A closed cylinder of `radius` standing on y = 0 up to `height`, as a lathe profile (top pole,
/// rim, bottom rim, bottom pole).
pub(super) fn cylinder_profile(radius: f32, height: f32) -> Vec<Vec2> {
    vec![Vec2::new(0.0, height), Vec2::new(radius, height), Vec2::new(radius, 0.0), Vec2::new(0.0, 0.0)]
}

/// A closed vessel (cup, bowl, pot, bin) with walls `wall` thick, as a lathe profile.
///
/// `outline` is the outer silhouette as (radius, height) points from the rim down to the foot,
/// radii positive and heights decreasing. The profile walks the solid's cross-section the way
/// [`push_lathe`] needs (as [`sphere_profile`] does, top pole to bottom pole): from the pole on the
/// inner floor, up the inner wall (the outline moved `wall` inwards, reversed), across the rim, down
/// the outer wall to the pole under the foot. So the vessel is one closed two-manifold with real
/// wall thickness, not an open band that would break shadow SVDAG's depth maps (docs/design.md §4.4).
pub(super) fn vessel_profile(outline: &[Vec2], wall: f32) -> Vec<Vec2> {
    let foot = outline.last().copied().unwrap_or(Vec2::ZERO);
    let floor = foot.y + wall;
    // Moved inwards, but never through the axis (a thin stem keeps half its radius).
    let inner = |p: Vec2| Vec2::new((p.x - wall).max(0.5 * p.x), p.y);
    // A flat inner floor out to the inner wall, then up the inner wall: every outline point above
    // the floor, bottom to top.
    let mut profile = vec![Vec2::new(0.0, floor), inner(foot.with_y(floor))];
    profile.extend(outline.iter().rev().filter(|p| p.y > floor).map(|&p| inner(p)));
    profile.extend_from_slice(outline);
    profile.push(Vec2::new(0.0, foot.y));
    profile
}

/// The transform that maps the cube `[-0.5, 0.5]³` of [`push_box`] onto the box `[min, max]`.
pub(super) fn box_between(min: Vec3, max: Vec3) -> Mat4 {
    Mat4::from_scale_rotation_translation(max - min, glam::Quat::IDENTITY, 0.5 * (min + max))
}

/// Appends the regular octahedron with vertices at `±1` on each axis, mapped by `transform`
/// (handedness-preserving): 6 shared vertices, 8 triangles, closed and wound outwards. The
/// smallest closed solid after the tetrahedron that looks the same from every side, for particles.
pub(super) fn push_octahedron(mesh: &mut Mesh, transform: Mat4) {
    let base = mesh.positions.len() as u32;
    // Vertex 2·axis + k is at +1 (k = 0) or −1 (k = 1) on `axis`.
    for axis in Vec3::AXES {
        mesh.positions.extend([axis, -axis].map(|corner| transform.transform_point3(corner)));
    }
    for octant in 0..8u32 {
        let k = |axis: u32| (octant >> axis) & 1;
        let [x, y, z] = [0, 1, 2].map(|axis| base + 2 * axis + k(axis));
        // (+x, +y, +z) is counter-clockwise seen from outside; each negated axis mirrors it.
        if (k(0) + k(1) + k(2)).is_multiple_of(2) { mesh.indices.push([x, y, z]) } else { mesh.indices.push([x, z, y]) }
    }
}
