//! A two-level hierarchy: one [`WideBvh`] per mesh in object space, shared by every
//! instance of it, under a binary [`Bvh`] over the instances' world-space boxes.
//!
//! A ray is carried into an instance's object space by the instance's inverse affine
//! map; its direction is not renormalised, so the parameter t of a hit is the same in
//! both spaces and hits of different instances compare directly.

use glam::{Affine3A, Vec3};

use super::triangle::TriangleHit;
use super::{Aabb, Bvh, Ray, SplitMethod, WideBvh, gamma};

/// One placement of a mesh.
#[derive(Clone, Copy, Debug)]
pub struct Instance {
    /// Maps the mesh's object space to world space.
    pub world_from_object: Affine3A,
    /// The inverse of `world_from_object`.
    pub object_from_world: Affine3A,
    /// Index of the mesh in [`TwoLevelBvh::meshes`].
    pub mesh: u32,
}

impl Instance {
    /// An instance of `mesh` placed by `world_from_object`; None when the map is not
    /// invertible (its inverse is not finite).
    pub fn new(world_from_object: Affine3A, mesh: u32) -> Option<Instance> {
        let object_from_world = world_from_object.inverse();
        object_from_world.is_finite().then_some(Instance {
            world_from_object,
            object_from_world,
            mesh,
        })
    }

    /// The ray in the instance's object space, with the same parameter t.
    #[inline]
    pub fn object_ray(&self, ray: &Ray) -> Ray {
        Ray {
            origin: self.object_from_world.transform_point3(ray.origin),
            dir: self.object_from_world.transform_vector3(ray.dir),
        }
    }
}

/// The world-space box of `object` placed by `m`, grown by a bound on the rounding of
/// the map so that it holds every point of the mesh as transformed in f32.
pub fn world_box(object: Aabb, m: &Affine3A) -> Aabb {
    if object.is_empty() {
        return Aabb::EMPTY;
    }
    let mut b = Aabb::EMPTY;
    let mut magnitude = Vec3::ZERO;
    for corner in 0..8 {
        let pick = |axis: usize| {
            if corner >> axis & 1 == 0 {
                object.min[axis]
            } else {
                object.max[axis]
            }
        };
        let p = Vec3::new(pick(0), pick(1), pick(2));
        b.grow(m.transform_point3(p));
        magnitude = magnitude.max(m.matrix3.abs() * p.abs() + Vec3::from(m.translation).abs());
    }
    let pad = Vec3::splat(gamma(4) * magnitude.max_element());
    Aabb::new(b.min - pad, b.max + pad)
}

/// Meshes in object space and the instances that place them, under one top-level BVH.
#[derive(Clone, Debug, Default)]
pub struct TwoLevelBvh {
    /// Bottom level: one hierarchy per mesh, in the mesh's object space.
    pub meshes: Vec<WideBvh>,
    /// The placements; a hit names its instance by index here.
    pub instances: Vec<Instance>,
    /// Top level over the instances' world boxes (empty without instances).
    pub top: Bvh,
}

impl TwoLevelBvh {
    /// Builds the top level over `instances` of `meshes`.
    pub fn new(meshes: Vec<WideBvh>, instances: Vec<Instance>, split: SplitMethod) -> Self {
        let boxes: Vec<Aabb> = instances
            .iter()
            .map(|i| world_box(meshes[i.mesh as usize].bounds, &i.world_from_object))
            .collect();
        let top = if boxes.is_empty() {
            Bvh::default()
        } else {
            Bvh::build(&boxes, split)
        };
        TwoLevelBvh {
            meshes,
            instances,
            top,
        }
    }

    /// Whether it holds no instance.
    pub fn is_empty(&self) -> bool {
        self.top.nodes.is_empty()
    }

    /// Bytes held: every mesh's hierarchy, the top level's nodes and indices, and the
    /// instances.
    pub fn bytes(&self) -> usize {
        self.meshes.iter().map(WideBvh::bytes).sum::<usize>()
            + size_of_val(self.top.nodes.as_slice())
            + size_of_val(self.top.prim_indices.as_slice())
            + size_of_val(self.instances.as_slice())
    }

    /// Bounds of every instance (empty without instances).
    pub fn bounds(&self) -> Aabb {
        if self.is_empty() {
            Aabb::EMPTY
        } else {
            self.top.bounds()
        }
    }

    /// Triangles drawn: each mesh's count once per instance of it.
    pub fn triangles_drawn(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.meshes[i.mesh as usize].triangles as u64)
            .sum()
    }

    /// The closest hit in (0, t_max): (instance, the mesh's triangle index, hit). Of
    /// hits at exactly the same t, the lowest instance wins, and within one instance
    /// the lowest triangle index.
    pub fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<(u32, u32, TriangleHit)> {
        // The winner's hit is kept here: the top level passes a hit on only when it
        // will keep it (closer, or as close with a lower instance), so the last one
        // passed on is the winner.
        let mut last: Option<(u32, u32, TriangleHit)> = None;
        let found = self.top.closest_hit(ray, t_max, &mut (), |i, tm| {
            let instance = &self.instances[i as usize];
            let (prim, h) =
                self.meshes[instance.mesh as usize].closest_hit(&instance.object_ray(ray), tm)?;
            let keep = last.is_none_or(|(li, _, lh)| h.t < lh.t || (h.t == lh.t && i < li));
            keep.then(|| {
                last = Some((i, prim, h));
                h.t
            })
        });
        found.and(last)
    }

    /// Visits triangles the ray meets in (0, t_max), in no particular order, until
    /// `visit(instance, prim, hit)` returns true (stop); returns whether it stopped.
    pub fn any_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(u32, u32, &TriangleHit) -> bool,
    ) -> bool {
        self.top.any_hit(ray, t_max, &mut (), |i| {
            let instance = &self.instances[i as usize];
            self.meshes[instance.mesh as usize]
                .any_hit(&instance.object_ray(ray), t_max, |p, h| visit(i, p, h))
        })
    }
}
