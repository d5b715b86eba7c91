//! The scene's geometry as the hot loops see it: world-space triangles and spheres in
//! flat arrays, each kind under its own BVH, with closest-hit and visibility queries.
//! Meshes that several entities share are not flattened: each is kept once in object
//! space under a two-level BVH ([`TwoLevelBvh`]) and read through its instances.

use std::collections::HashMap;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use super::crossings::Crossings;
use super::materials::Materials;
use super::plan::RenderPlan;
use crate::accel::leaf::NO_PRIM;
use crate::accel::sphere::{sphere_roots, sphere_uv};
use crate::accel::triangle::{RayShear, TriangleHit, intersect_triangle_sheared};
use crate::accel::{
    Aabb, Bvh, Instance, Ray, RayLanes, SplitMethod, TraversalStats, TraversalVisitor, TwoLevelBvh,
    WideBvh, gamma, intersect_sphere,
};
use crate::scene::{Acceleration, BvhSplit, Mesh, MeshData, Settings, Sphere, Transform};
use crate::stats::{RenderStats, Stage};

/// Which kind of primitive a hit is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimKind {
    /// A triangle of a mesh.
    Triangle,
    /// An analytic sphere.
    Sphere,
}

/// Observes a query over the scene's hierarchies: the BVH visitor, told which
/// hierarchy it is in so node and primitive ids can be told apart.
pub trait GeometryVisitor: TraversalVisitor {
    /// Whether it observes anything: queries for a visitor that does not take the
    /// wide (8-wide) triangle BVH, whose nodes are not the binary ones the observers name.
    const OBSERVES: bool = true;
    /// Called before traversing the hierarchy over primitives of `kind`.
    fn begin_hierarchy(&mut self, _kind: PrimKind) {}
}

impl GeometryVisitor for () {
    const OBSERVES: bool = false;
}

impl GeometryVisitor for TraversalStats {}

/// The closest intersection of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// Primitive index within its kind.
    pub prim: u32,
    /// Triangle or sphere.
    pub kind: PrimKind,
    /// Barycentric weights of the triangle's vertices (zero for spheres).
    pub bary: Vec3,
    /// For a triangle of an instanced mesh, the instance (index into
    /// `SceneGeometry::instanced.instances`); `prim` is then the mesh's own triangle index.
    pub instance: Option<u32>,
    /// For a flattened triangle, where its vertices sit in `SceneGeometry::tri_wide`'s
    /// leaves ([`WideBvh::triangle_at`]; see [`SceneGeometry::lane`]); zero otherwise.
    pub lane: u32,
}

/// A triangle as shading reads it, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleData {
    /// Vertex positions.
    pub positions: [Vec3; 3],
    /// Vertex normals (unit).
    pub normals: [Vec3; 3],
    /// Vertex texture coordinates.
    pub texcoords: [Vec2; 3],
    /// Material index.
    pub material: u32,
    /// Bound on the rounding added by an instance's transform (zero when flattened):
    /// its vertices mapped to world space, and a ray origin mapped back.
    pub transform_error: Vec3,
}

/// World-space geometry in flat arrays, and one BVH per primitive kind. The flattened
/// triangles' vertex positions are held once, in `tri_wide`'s leaves
/// ([`SceneGeometry::positions`]).
#[derive(Resource, Clone, Debug, Default)]
pub struct SceneGeometry {
    /// Triangle vertex normals (unit).
    pub tri_normals: Vec<[Vec3; 3]>,
    /// Triangle vertex texture coordinates.
    pub tri_texcoords: Vec<[Vec2; 3]>,
    /// Material index of each triangle.
    pub tri_material: Vec<u32>,
    /// Binary hierarchy over the triangles, which `tri_wide` is collapsed from: kept
    /// only for observers (see [`RenderPlan::binary_triangle_bvh`]), else empty.
    pub tri_bvh: Bvh,
    /// `tri_bvh` collapsed to 8-wide nodes with the triangles in leaf order: what
    /// unobserved queries traverse, and where every query reads a triangle's vertices.
    pub tri_wide: WideBvh,
    /// Where each flattened triangle sits in `tri_wide`'s leaves: kept with `tri_bvh`
    /// only, for its queries, which name triangles by index (a render's hits carry it).
    pub tri_lanes: Vec<u32>,
    /// Spheres (world space).
    pub spheres: Vec<Sphere>,
    /// Material index of each sphere.
    pub sphere_material: Vec<u32>,
    /// Hierarchy over the spheres.
    pub sphere_bvh: Bvh,
    /// Meshes used by two or more entities, once each in object space, and their
    /// instances under a top-level BVH (empty when no mesh is shared).
    pub instanced: TwoLevelBvh,
    /// The vertices and triangles of each mesh in `instanced.meshes`: the scene's own,
    /// shared, not copied.
    pub instanced_meshes: Vec<Arc<MeshData>>,
    /// Material index of each instance.
    pub instance_material: Vec<u32>,
}

/// The one mapping from the scene's [`BvhSplit`] to accel's [`SplitMethod`]: scene sits
/// below accel, so it cannot name `SplitMethod` itself.
fn split_method(s: &Settings) -> SplitMethod {
    match s.bvh_split {
        BvhSplit::SahBinned => SplitMethod::SahBinned,
        BvhSplit::Median => SplitMethod::Median,
    }
}

fn build(bounds: &[Aabb], s: &Settings) -> Bvh {
    match s.acceleration {
        Acceleration::Bvh => Bvh::build(bounds, split_method(s)),
        Acceleration::None => Bvh::single_leaf(bounds),
    }
}

/// [`build`] over triangles, whose tree may cut them by spatial splits.
fn build_triangles(positions: &[[Vec3; 3]], s: &Settings) -> Bvh {
    match s.acceleration {
        Acceleration::Bvh => Bvh::build_triangles(positions, split_method(s)),
        Acceleration::None => {
            let bounds: Vec<Aabb> = positions.iter().map(|p| Aabb::from_points(p)).collect();
            Bvh::single_leaf(&bounds)
        }
    }
}

/// Transforms every mesh used once to world space and builds the triangle BVH; meshes
/// used by two or more entities get one object-space BVH each, shared by their instances.
/// The binary tree is kept after collapsing only when the plan says an observer walks it.
pub fn build_triangle_bvh(
    settings: Res<Settings>,
    plan: Res<RenderPlan>,
    meshes: Query<(&Mesh, &Transform, &crate::scene::MaterialRef)>,
    materials: Res<Materials>,
    mut geometry: ResMut<SceneGeometry>,
    mut stats: ResMut<RenderStats>,
) {
    let g = &mut *geometry;
    // Kept until the wide tree holds them.
    let mut positions: Vec<[Vec3; 3]> = Vec::new();
    let uses = mesh_uses(meshes.iter().map(|(m, _, _)| m));
    // Without acceleration every triangle is tested against every ray, instances too:
    // a top-level BVH would be acceleration the setting asks to leave out.
    let instancing = settings.acceleration == Acceleration::Bvh;
    // Index in `instanced_meshes` of each shared mesh, in order of first use.
    let mut mesh_index: HashMap<*const MeshData, u32> = HashMap::new();
    let mut instances = Vec::new();
    for (mesh, transform, material) in &meshes {
        let m = transform.world_from_object;
        let material = materials.index_of.get(&material.0).copied().unwrap_or(0);
        let key = Arc::as_ptr(&mesh.data);
        if instancing && uses[&key] >= 2 {
            let next = mesh_index.len() as u32;
            let index = *mesh_index.entry(key).or_insert(next);
            // A map without an inverse (zero scale) leaves its instance flattened.
            if let Some(instance) = Instance::new(m, index) {
                if index == next {
                    g.instanced_meshes.push(mesh.data.clone());
                }
                instances.push(instance);
                g.instance_material.push(material);
                continue;
            }
            if index == next {
                mesh_index.remove(&key);
            }
        }
        let normal_from_object = m.matrix3.inverse().transpose();
        let v = &mesh.data.vertices;
        for t in &mesh.data.triangles {
            let [a, b, c] = t.map(|i| &v[i as usize]);
            positions.push([a, b, c].map(|v| m.transform_point3(v.position)));
            g.tri_normals.push([a, b, c].map(|v| {
                (normal_from_object * glam::Vec3A::from(v.normal))
                    .try_normalize()
                    .map_or(Vec3::Z, Vec3::from)
            }));
            g.tri_texcoords.push([a.texcoord, b.texcoord, c.texcoord]);
            g.tri_material.push(material);
        }
    }
    let flattened = positions.len();
    let bvh = build_triangles(&positions, &settings);
    if plan.binary_triangle_bvh {
        g.tri_bvh = bvh;
        g.collapse_triangle_bvh(&positions);
    } else {
        g.tri_wide = WideBvh::collapse(&bvh, &positions);
    }
    drop(positions);
    let bottom: Vec<WideBvh> = g
        .instanced_meshes
        .iter()
        .map(|data| object_bvh(data, &settings))
        .collect();
    let stored: usize = bottom.iter().map(|b| b.triangles).sum();
    g.instanced = TwoLevelBvh::new(bottom, instances, split_method(&settings));
    stats.record(Stage::BuildTriangleBvh, (flattened + stored) as u64);
}

/// How many entities use each mesh's data; a mesh used by two or more is instanced.
pub fn mesh_uses<'a>(meshes: impl Iterator<Item = &'a Mesh>) -> HashMap<*const MeshData, u32> {
    let mut uses = HashMap::new();
    for mesh in meshes {
        *uses.entry(Arc::as_ptr(&mesh.data)).or_default() += 1;
    }
    uses
}

/// The wide BVH of a mesh's triangles in its object space.
fn object_bvh(data: &MeshData, settings: &Settings) -> WideBvh {
    let v = &data.vertices;
    let positions: Vec<[Vec3; 3]> = data
        .triangles
        .iter()
        .map(|t| t.map(|i| v[i as usize].position))
        .collect();
    WideBvh::collapse(&build_triangles(&positions, settings), &positions)
}

/// Gathers the spheres and builds their BVH.
pub fn build_sphere_bvh(
    settings: Res<Settings>,
    spheres: Query<(&Sphere, &crate::scene::MaterialRef)>,
    materials: Res<Materials>,
    mut geometry: ResMut<SceneGeometry>,
    mut stats: ResMut<RenderStats>,
) {
    let g = &mut *geometry;
    for (s, material) in &spheres {
        g.spheres.push(*s);
        g.sphere_material
            .push(materials.index_of.get(&material.0).copied().unwrap_or(0));
    }
    let bounds: Vec<Aabb> = g
        .spheres
        .iter()
        .map(|s| Aabb {
            min: s.center - Vec3::splat(s.radius),
            max: s.center + Vec3::splat(s.radius),
        })
        .collect();
    g.sphere_bvh = build(&bounds, &settings);
    stats.record(Stage::BuildSphereBvh, bounds.len() as u64);
}

impl SceneGeometry {
    /// Makes `tri_wide` from `tri_bvh` and the flattened triangles' `positions`, which
    /// it then holds.
    pub fn collapse_triangle_bvh(&mut self, positions: &[[Vec3; 3]]) {
        self.tri_wide = WideBvh::collapse(&self.tri_bvh, positions);
        self.tri_lanes = self.tri_wide.prim_lanes();
    }

    /// Where flattened triangle `prim` sits in `tri_wide`'s leaves: from `tri_lanes`
    /// where kept, else searched (observers and tests only; a render's hits carry it).
    /// Panics when `prim` is not a flattened triangle of this scene: a caller's bug,
    /// which a fallback lane would turn into another triangle's vertices.
    pub fn lane(&self, prim: u32) -> u32 {
        if let Some(&lane) = self.tri_lanes.get(prim as usize) {
            return lane;
        }
        // Padding lanes hold `NO_PRIM`, which is no triangle's index.
        (prim != NO_PRIM)
            .then(|| self.tri_wide.leaves.prims().position(|p| p == prim))
            .flatten()
            .unwrap_or_else(|| panic!("triangle {prim} is not in the scene's wide BVH"))
            as u32
    }

    /// The vertices of flattened triangle `prim`.
    #[inline]
    pub fn positions(&self, prim: u32) -> [Vec3; 3] {
        self.tri_wide.triangle_at(self.lane(prim))
    }

    /// The vertices of every flattened triangle, in order.
    pub fn all_positions(&self) -> Vec<[Vec3; 3]> {
        self.tri_wide.positions()
    }

    /// Flattened triangles (those of meshes used once).
    pub fn triangles_flattened(&self) -> usize {
        self.tri_wide.triangles
    }

    /// Whether queries observed by `V` traverse the wide triangle BVH: unobserved ones,
    /// and observed ones when the binary tree was dropped (they then still find the
    /// render's hits, but see no triangle nodes).
    pub(super) fn use_wide<V: GeometryVisitor>(&self) -> bool {
        !self.tri_wide.nodes.is_empty() && (!V::OBSERVES || self.tri_bvh.nodes.is_empty())
    }

    /// The closest hit in (0, t_max), triangles and spheres alike.
    pub fn intersect<V: GeometryVisitor>(
        &self,
        ray: &Ray,
        t_max: f32,
        visitor: &mut V,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        if self.use_wide::<V>() {
            if let Some((prim, lane, h)) = self.tri_wide.closest_hit_at(ray, t_max) {
                t_max = h.t;
                best = Some(Hit {
                    lane,
                    ..triangle_hit(prim, &h)
                });
            }
        } else if !self.tri_bvh.nodes.is_empty() {
            visitor.begin_hierarchy(PrimKind::Triangle);
            let shear = RayShear::new(ray);
            // The winner's hit is kept here instead of re-running its test: a hit is
            // passed on only when the traversal will keep it (closer, or as close with a
            // lower index), so the last one passed on is the winner.
            let mut last: Option<(u32, TriangleHit)> = None;
            let found = self.tri_bvh.closest_hit(ray, t_max, visitor, |p, tm| {
                let [a, b, c] = self.positions(p);
                let h = intersect_triangle_sheared(&shear, ray.origin, a, b, c, tm)?;
                let keep = last.is_none_or(|(lp, lh)| h.t < lh.t || (h.t == lh.t && p < lp));
                keep.then(|| {
                    last = Some((p, h));
                    h.t
                })
            });
            if let (Some((prim, _)), Some((_, h))) = (found, last) {
                t_max = h.t;
                best = Some(Hit {
                    lane: self.lane(prim),
                    ..triangle_hit(prim, &h)
                });
            }
        }
        self.intersect_beyond_triangles(ray, best, t_max, visitor)
    }

    /// `best`, the closest hit among the flattened triangles in (0, t_max) (t_max its t
    /// if any), or a closer one on an instance or a sphere.
    #[inline]
    fn intersect_beyond_triangles<V: GeometryVisitor>(
        &self,
        ray: &Ray,
        best: Option<Hit>,
        t_max: f32,
        visitor: &mut V,
    ) -> Option<Hit> {
        self.closest_beyond_triangles(ray, t_max, visitor).or(best)
    }

    /// The closest hit in (0, t_max) on an instance or a sphere, if any.
    #[inline]
    pub(super) fn closest_beyond_triangles<V: GeometryVisitor>(
        &self,
        ray: &Ray,
        mut t_max: f32,
        visitor: &mut V,
    ) -> Option<Hit> {
        let mut best = None;
        // After the flattened triangles and strictly closer: of hits at the same t,
        // flattened triangles win over instances.
        if !self.instanced.is_empty()
            && let Some((instance, prim, h)) = self.instanced.closest_hit(ray, t_max)
        {
            t_max = h.t;
            best = Some(Hit {
                instance: Some(instance),
                ..triangle_hit(prim, &h)
            });
        }
        if !self.sphere_bvh.nodes.is_empty() {
            visitor.begin_hierarchy(PrimKind::Sphere);
            let found = self.sphere_bvh.closest_hit(ray, t_max, visitor, |p, tm| {
                let s = &self.spheres[p as usize];
                intersect_sphere(ray, s.center, s.radius, tm)
            });
            if let Some((prim, t)) = found {
                best = Some(Hit {
                    t,
                    prim,
                    kind: PrimKind::Sphere,
                    bary: Vec3::ZERO,
                    instance: None,
                    lane: 0,
                });
            }
        }
        best
    }

    /// Whether anything lies on the ray in (0, t_max).
    pub fn occluded<V: GeometryVisitor>(&self, ray: &Ray, t_max: f32, visitor: &mut V) -> bool {
        let tris = if self.use_wide::<V>() {
            self.tri_wide.any_hit(ray, t_max, |_, _| true)
        } else {
            // The shear is per ray: computed once here, not in every triangle test.
            !self.tri_bvh.nodes.is_empty() && {
                let shear = RayShear::new(ray);
                self.tri_bvh.any_hit(ray, t_max, visitor, |p| {
                    let [a, b, c] = self.positions(p);
                    intersect_triangle_sheared(&shear, ray.origin, a, b, c, t_max).is_some()
                })
            }
        };
        tris || self.occluded_beyond_triangles(ray, t_max, visitor)
    }

    /// Whether an instanced triangle or a sphere lies on the ray in (0, t_max).
    fn occluded_beyond_triangles<V: GeometryVisitor>(
        &self,
        ray: &Ray,
        t_max: f32,
        visitor: &mut V,
    ) -> bool {
        (!self.instanced.is_empty() && self.instanced.any_hit(ray, t_max, |_, _, _| true))
            || (!self.sphere_bvh.nodes.is_empty()
                && self.sphere_bvh.any_hit(ray, t_max, visitor, |p| {
                    let s = &self.spheres[p as usize];
                    intersect_sphere(ray, s.center, s.radius, t_max).is_some()
                }))
    }

    /// [`Self::occluded`] (unobserved) of up to [`PACKET`](crate::accel::PACKET) rays
    /// with one `t_max`: bit `i` set when `rays[i]` is occluded ([`Self::occluded_lanes`]
    /// of them in lanes).
    pub fn occluded_packet(&self, rays: &[Ray], t_max: f32) -> u32 {
        self.occluded_lanes(&RayLanes::from_rays(rays), t_max)
    }

    /// [`Self::occluded`] (unobserved) of the active lanes of `rays` with one `t_max`:
    /// bit `i` set when lane `i`'s ray is occluded. The flattened triangles take the
    /// lanes as one packet (`WideBvh::occluded_lanes`); instances and spheres, each ray
    /// they did not occlude.
    pub fn occluded_lanes(&self, rays: &RayLanes, t_max: f32) -> u32 {
        let wide = self.use_wide::<()>();
        let mut blocked = if wide {
            self.tri_wide.occluded_lanes(rays, t_max)
        } else {
            0
        };
        if wide && self.instanced.is_empty() && self.sphere_bvh.nodes.is_empty() {
            return blocked;
        }
        for i in rays.lanes() {
            let ray = rays.ray(i);
            let hit = blocked & (1 << i) == 0
                && if wide {
                    self.occluded_beyond_triangles(&ray, t_max, &mut ())
                } else {
                    self.occluded(&ray, t_max, &mut ())
                };
            blocked |= (hit as u32) << i;
        }
        blocked
    }

    /// Light transmitted along the ray through (0, t_max): the product over every surface
    /// crossed of `(1 - alpha) * (1 - (1 - kd) * alpha)`; zero at the first opaque one.
    /// A ray through the edge shared by two triangles of one surface hits both at the same
    /// t; such twins are counted once, as is a triangle met in two leaves (a spatial split
    /// leaves it in both), whose crossings are equal and so sorted side by side.
    pub fn transmittance<V: GeometryVisitor>(
        &self,
        ray: &Ray,
        t_max: f32,
        materials: &Materials,
        visitor: &mut V,
    ) -> Vec3 {
        // (t, material, uv) of every transparent surface crossed; opaque ones stop the walk.
        let mut crossings = Crossings::default();
        let opaque = |material: u32| materials.list[material as usize].alpha >= 1.0;
        let mut cross = |material: u32, texcoords: &dyn Fn() -> [Vec2; 3], h: &TriangleHit| {
            if opaque(material) {
                return true;
            }
            let [ta, tb, tc] = texcoords();
            crossings.push((h.t, material, h.b0 * ta + h.b1 * tb + h.b2 * tc));
            false
        };
        let flat = |p: u32| self.tri_texcoords[p as usize];
        let blocked = if self.use_wide::<V>() {
            self.tri_wide.any_hit(ray, t_max, |p, h| {
                cross(self.tri_material[p as usize], &|| flat(p), h)
            })
        } else {
            !self.tri_bvh.nodes.is_empty() && {
                let shear = RayShear::new(ray);
                self.tri_bvh.any_hit(ray, t_max, visitor, |p| {
                    let [a, b, c] = self.positions(p);
                    intersect_triangle_sheared(&shear, ray.origin, a, b, c, t_max)
                        .is_some_and(|h| cross(self.tri_material[p as usize], &|| flat(p), &h))
                })
            }
        } || (!self.instanced.is_empty()
            && self.instanced.any_hit(ray, t_max, |i, p, h| {
                let material = self.instance_material[i as usize];
                cross(material, &|| self.instanced_texcoords(i, p), h)
            }));
        if blocked {
            return Vec3::ZERO;
        }
        if !self.sphere_bvh.nodes.is_empty() {
            let blocked = self.sphere_bvh.any_hit(ray, t_max, visitor, |p| {
                let s = &self.spheres[p as usize];
                let Some((t0, t1)) = sphere_roots(ray, s.center, s.radius) else {
                    return false;
                };
                let material = self.sphere_material[p as usize];
                // A sphere is two surfaces: a ray through it crosses both roots.
                for t in [t0, t1] {
                    if !(t > 0.0 && t < t_max) {
                        continue;
                    }
                    if opaque(material) {
                        return true;
                    }
                    let n = (ray.origin + t * ray.dir - s.center) / s.radius;
                    crossings.push((t, material, sphere_uv(n)));
                }
                false
            });
            if blocked {
                return Vec3::ZERO;
            }
        }
        let crossings = crossings.sorted();
        let mut tint = Vec3::ONE;
        let mut previous: Option<(f32, u32)> = None;
        for &(t, material, uv) in crossings {
            let twin = previous.is_some_and(|(pt, pm)| pm == material && t - pt <= 1e-5 * t);
            previous = Some((t, material));
            if twin {
                continue;
            }
            let alpha = materials.list[material as usize].alpha;
            let kd = materials.kd_at(material, uv);
            tint *= (1.0 - alpha) * (Vec3::ONE - (Vec3::ONE - kd) * alpha);
        }
        tint
    }

    /// Triangles drawn: the flattened ones and every instance's.
    pub fn triangles_drawn(&self) -> u64 {
        self.triangles_flattened() as u64 + self.instanced.triangles_drawn()
    }

    /// Triangles stored: the flattened ones and each instanced mesh's once.
    pub fn triangles_stored(&self) -> u64 {
        let instanced: usize = self.instanced.meshes.iter().map(|m| m.triangles).sum();
        (self.triangles_flattened() + instanced) as u64
    }

    /// Bytes the render's triangle queries read: the wide BVH (nodes, triangle data,
    /// which holds the flattened positions, indices), and for instanced meshes their BVHs, the
    /// top level, the instances and the meshes' vertices and indices.
    pub fn triangle_bytes(&self) -> usize {
        let meshes: usize = self
            .instanced_meshes
            .iter()
            .map(|m| size_of_val(m.vertices.as_slice()) + size_of_val(m.triangles.as_slice()))
            .sum();
        self.tri_wide.bytes() + self.instanced.bytes() + meshes
    }

    /// The texture coordinates of triangle `prim` of the mesh of `instance`.
    fn instanced_texcoords(&self, instance: u32, prim: u32) -> [Vec2; 3] {
        let mesh =
            &self.instanced_meshes[self.instanced.instances[instance as usize].mesh as usize];
        mesh.triangles[prim as usize].map(|k| mesh.vertices[k as usize].texcoord)
    }

    /// The hit triangle of `hit` (a triangle hit) in world space.
    pub fn triangle(&self, hit: &Hit) -> TriangleData {
        let i = hit.prim as usize;
        let Some(instance) = hit.instance else {
            return TriangleData {
                positions: self.tri_wide.triangle_at(hit.lane),
                normals: self.tri_normals[i],
                texcoords: self.tri_texcoords[i],
                material: self.tri_material[i],
                transform_error: Vec3::ZERO,
            };
        };
        let inst = &self.instanced.instances[instance as usize];
        let mesh = &self.instanced_meshes[inst.mesh as usize];
        let vertices = mesh.triangles[i].map(|k| &mesh.vertices[k as usize]);
        // The same arithmetic as flattening in `build_triangle_bvh`.
        let m = &inst.world_from_object;
        let normal_from_object = inst.object_from_world.matrix3.transpose();
        let positions = vertices.map(|v| m.transform_point3(v.position));
        // Vertices mapped to world space round by gamma(3) of |M||v| + |T|; a ray origin
        // mapped back to object space by gamma(3) of |M^-1||p| + |T^-1|, which is |M|
        // times that in world space. gamma(4) covers the products of the two.
        let (ma, ia) = (m.matrix3.abs(), inst.object_from_world.matrix3.abs());
        let (mt, it) = (
            Vec3::from(m.translation).abs(),
            Vec3::from(inst.object_from_world.translation).abs(),
        );
        let object = vertices
            .iter()
            .fold(Vec3::ZERO, |a, v| a.max(v.position.abs()));
        let world = positions.iter().fold(Vec3::ZERO, |a, p| a.max(p.abs()));
        let transform_error = gamma(4) * (ma * object + mt + ma * (ia * world + it));
        TriangleData {
            positions,
            normals: vertices.map(|v| {
                (normal_from_object * glam::Vec3A::from(v.normal))
                    .try_normalize()
                    .map_or(Vec3::Z, Vec3::from)
            }),
            texcoords: vertices.map(|v| v.texcoord),
            material: self.instance_material[instance as usize],
            transform_error,
        }
    }

    /// Bounds of all geometry (empty when there is none).
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        b = b.union(self.instanced.bounds());
        if !self.tri_wide.nodes.is_empty() {
            b = b.union(self.tri_wide.bounds);
        } else if !self.tri_bvh.nodes.is_empty() {
            b = b.union(self.tri_bvh.bounds());
        }
        if !self.sphere_bvh.nodes.is_empty() {
            b = b.union(self.sphere_bvh.bounds());
        }
        b
    }
}

/// The scene's hit record of triangle `prim`.
pub(super) fn triangle_hit(prim: u32, h: &TriangleHit) -> Hit {
    Hit {
        t: h.t,
        prim,
        kind: PrimKind::Triangle,
        bary: Vec3::new(h.b0, h.b1, h.b2),
        instance: None,
        lane: 0,
    }
}

#[cfg(test)]
#[path = "geometry_tests.rs"]
mod tests;
