//! A scene: one merged triangle mesh plus named objects, an optional camera and light, and, for a
//! frame of an animated scene, the animation it belongs to.

use std::sync::Arc;

use glam::Vec3;

use crate::camera::CameraSpec;
use crate::geom::Aabb;
use crate::mesh::{Dropped, Mesh};

/// A triangle as its three corners: the geometry buffer every triangle structure's kernel reads
/// (shared, built once per scene, not counted in any structure's memory).
pub type Triangle = [Vec3; 3];

/// A named range of the scene's triangles, e.g. one closed object of the `room` scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub name: String,
    pub first_triangle: u32,
    pub triangle_count: u32,
    /// True when the object is a closed (watertight, two-manifold) surface: shadow SVDAG's
    /// double depth maps rely on it (docs/design.md §4.4).
    pub closed: bool,
}

/// Everything a structure is built from. Triangle ids are indices into `mesh.indices`.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The name on the command line (`bunny`, `grass-10k`) or the file's stem.
    pub name: String,
    pub provenance: String,
    pub mesh: Mesh,
    pub objects: Vec<Object>,
    /// The scene's own camera, if it has one; otherwise [`CameraSpec::canonical`] is used.
    pub camera: Option<CameraSpec>,
    /// A point light, for shadow workloads.
    pub light: Option<Vec3>,
    /// The animation this scene is a frame of ([`Animation::frame`]), or `None` for a static
    /// scene. Every frame of one animation has the same triangles, objects and bounds; only vertex
    /// positions move, so the temporal SVDAG can voxelise all frames into one grid (docs/design.md §6).
    /// Anything that changes the triangles (`@sub<k>`) drops it.
    pub animation: Option<Animation>,
    /// Triangles dropped when the scene was loaded ([`Scene::drop_unusable_triangles`]).
    pub dropped: Dropped,
}

impl Scene {
    /// A scene of one mesh, as loaded from a file.
    pub fn from_mesh(name: impl Into<String>, mesh: Mesh) -> Self {
        let object = Object {
            name: mesh.name.clone(),
            first_triangle: 0,
            triangle_count: mesh.indices.len() as u32,
            closed: false,
        };
        Self {
            name: name.into(),
            provenance: mesh.provenance.clone(),
            mesh,
            objects: vec![object],
            camera: None,
            light: None,
            animation: None,
            dropped: Dropped::default(),
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.mesh.triangle_count()
    }

    pub fn bounds(&self) -> Aabb {
        self.mesh.bounds()
    }

    /// The camera to render with: the scene's own, or the canonical one of docs/design.md §3.
    pub fn camera_spec(&self) -> CameraSpec {
        self.camera.unwrap_or_else(|| CameraSpec::canonical(self.bounds()))
    }

    /// The point light for shadow rays: the scene's own, or one above and behind the canonical eye.
    pub fn light_position(&self) -> Vec3 {
        self.light.unwrap_or_else(|| {
            let b = self.bounds().framed();
            b.center() + b.diagonal() * Vec3::new(-0.4, 1.0, 0.6)
        })
    }

    /// Drops the mesh's degenerate and duplicated triangles ([`Mesh::drop_unusable`]) and
    /// narrows the objects' triangle ranges to what is left; adds them to [`Scene::dropped`].
    pub fn drop_unusable_triangles(&mut self) -> Dropped {
        let (dropped, keep) = self.mesh.drop_unusable();
        if dropped.total() > 0 {
            // kept_before[t]: triangle t's index once the dropped ones before it are gone.
            let kept_before: Vec<u32> = std::iter::once(0)
                .chain(keep.iter().scan(0u32, |n, &k| {
                    *n += u32::from(k);
                    Some(*n)
                }))
                .collect();
            for o in &mut self.objects {
                let (first, end) = (o.first_triangle as usize, (o.first_triangle + o.triangle_count) as usize);
                (o.first_triangle, o.triangle_count) = (kept_before[first], kept_before[end] - kept_before[first]);
            }
        }
        self.dropped.degenerate += dropped.degenerate;
        self.dropped.duplicate += dropped.duplicate;
        dropped
    }

    /// The triangle soup every triangle structure's kernel reads (see [`Triangle`]).
    pub fn triangles(&self) -> Arc<[Triangle]> {
        (0..self.mesh.triangle_count()).map(|i| self.mesh.triangle(i)).collect()
    }
}

/// A deterministic animation: frame `t` of it is a [`Scene`] computed directly from the seed and
/// `t` ([`Animation::frame`], in `crate::anim`, whose documentation says what all frames share).
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// The animated scene's name (`kitchen-anim`, …).
    pub name: String,
    pub seed: u64,
    /// Frames 0..frames form the animation.
    pub frames: u32,
    pub(crate) generator: Generator,
}

/// Which procedural generator an animation's frames come from (`crate::anim` runs it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Generator {
    /// A kitchen with a few moving objects: mostly static, like BART Kitchen.
    Kitchen,
    /// Walking articulated robots: mostly dynamic, like BART Robots.
    Robots,
    /// Rising, tumbling particles over a hearth: dynamic and random, like BART Fire.
    Fire,
}
