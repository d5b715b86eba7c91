//! From a hit to a shading point: position with its error bound, normals facing the
//! ray, texture coordinate; and robust spawning of rays off the surface.
//!
//! Offsets follow pbrt's approach (Pharr, Jakob, Humphreys, "Physically Based Rendering",
//! 3rd ed., 3.9): the hit point carries a conservative bound on its rounding error, and
//! new rays start just outside that error box along the geometric normal, rounded away
//! from the surface. The offset therefore scales with the hit point's magnitude and
//! works at 1e-4 and at 1e6 scene scale alike, unlike a fixed epsilon.

use glam::{Vec2, Vec3};

use crate::accel::sphere::sphere_uv;
use crate::accel::{Ray, gamma};
use crate::trace::geometry::{Hit, PrimKind, SceneGeometry};

/// Fraction of a shadow ray's length left out at the light end, so that a surface the
/// light sample sits on does not shadow it.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// A shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Position.
    pub p: Vec3,
    /// Conservative bound on the absolute rounding error of each component of `p`.
    pub p_error: Vec3,
    /// Geometric normal, turned to face the incoming ray.
    pub ng: Vec3,
    /// Shading normal (interpolated or geometric), on the same side as `ng`.
    pub n: Vec3,
    /// Texture coordinate.
    pub uv: Vec2,
    /// Material index.
    pub material: u32,
}

/// Builds the shading point of `hit` on `ray`.
pub fn surface_at(
    geometry: &SceneGeometry,
    ray: &Ray,
    hit: &Hit,
    interpolate_normals: bool,
) -> Surface {
    let (p, p_error, ng, n, uv, material) = match (hit.kind, hit.instance) {
        // A flattened triangle: its parts read where they are, none copied or unused.
        (PrimKind::Triangle, None) => {
            let i = hit.prim as usize;
            let positions = geometry.tri_wide.triangle_at(hit.lane);
            let normals = interpolate_normals.then(|| &geometry.tri_normals[i]);
            let (p, p_error, ng, n, uv) = triangle_point(
                positions,
                normals,
                &geometry.tri_texcoords[i],
                hit.bary,
                None,
            );
            (p, p_error, ng, n, uv, geometry.tri_material[i])
        }
        (PrimKind::Triangle, Some(_)) => {
            let tri = geometry.triangle(hit);
            let normals = interpolate_normals.then_some(&tri.normals);
            let (p, p_error, ng, n, uv) = triangle_point(
                tri.positions,
                normals,
                &tri.texcoords,
                hit.bary,
                Some(tri.transform_error),
            );
            (p, p_error, ng, n, uv, tri.material)
        }
        (PrimKind::Sphere, _) => {
            let s = &geometry.spheres[hit.prim as usize];
            let raw = ray.origin + hit.t * ray.dir;
            // Re-project onto the sphere: this removes most of the error of `o + t d`.
            let local = (raw - s.center).normalize_or(Vec3::Y);
            let p = s.center + local * s.radius;
            let p_error = gamma(5) * ((local * s.radius).abs() + s.center.abs());
            (
                p,
                p_error,
                local,
                local,
                sphere_uv(local),
                geometry.sphere_material[hit.prim as usize],
            )
        }
    };
    let ng = if ng.dot(ray.dir) > 0.0 { -ng } else { ng };
    let n = if n.dot(ng) < 0.0 { -n } else { n };
    Surface {
        p,
        p_error,
        ng,
        n,
        uv,
        material,
    }
}

/// Position, its error bound, geometric and shading normals and texture coordinate at
/// barycentric weights `b` of a triangle; `normals` for interpolated shading normals,
/// `transform_error` for an instance's (none for flattened triangles, where it is zero).
#[inline(always)]
fn triangle_point(
    positions: [Vec3; 3],
    normals: Option<&[Vec3; 3]>,
    texcoords: &[Vec2; 3],
    b: Vec3,
    transform_error: Option<Vec3>,
) -> (Vec3, Vec3, Vec3, Vec3, Vec2) {
    let [p0, p1, p2] = positions;
    let p = b.x * p0 + b.y * p1 + b.z * p2;
    let p_error = gamma(7) * ((b.x * p0).abs() + (b.y * p1).abs() + (b.z * p2).abs());
    // Adding a zero error would change nothing: the bound is a sum of absolute values,
    // never -0.
    let p_error = transform_error.map_or(p_error, |e| p_error + e);
    let ng = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Z);
    let n = match normals {
        Some([n0, n1, n2]) => {
            // Clamp so rounding just outside the triangle cannot flip the blend.
            let w = b.max(Vec3::ZERO);
            (w.x * *n0 + w.y * *n1 + w.z * *n2).normalize_or(ng)
        }
        None => ng,
    };
    let [t0, t1, t2] = *texcoords;
    let uv = b.x * t0 + b.y * t1 + b.z * t2;
    (p, p_error, ng, n, uv)
}

/// The least magnitude of an origin coordinate that [`offset_ray_origin`] moves off a
/// surface: 2^-100, a normal float whose products with anything above 2^-26 stay normal.
pub const MIN_OFFSET_COORDINATE: f32 = 7.888_609e-31;

/// A ray origin just off the surface at `p`, on the side of `ng` that `w` points to.
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    let side = if w.dot(ng) < 0.0 { -ng } else { ng };
    offset_ray_origin_towards(p, p_error, ng, side)
}

/// [`offset_ray_origin`] with its side given: `side` is `ng` or `-ng`, the one `w` is on.
/// With `w = ng` the side is `ng` itself (`ng.ng`, a sum of squares or NaN, is never
/// below 0), so a shadow ray's origin needs no test of it.
pub fn offset_ray_origin_towards(p: Vec3, p_error: Vec3, ng: Vec3, side: Vec3) -> Vec3 {
    let mut po = p + ng.abs().dot(p_error) * side;
    // Round away from the surface, so the origin leaves it even where the error bound
    // is zero (a plane through the origin of an axis) and the addition rounds back.
    // Off such a plane, not to the next float: that is subnormal (1.4e-45), and every
    // box and triangle test of the ray then works on subnormals, which x86 handles in
    // microcode (the Cornell render, whose floor is y = 0, took twice as long).
    for i in 0..3 {
        if side[i] != 0.0 && po[i].abs() < MIN_OFFSET_COORDINATE {
            po[i] = MIN_OFFSET_COORDINATE.copysign(side[i]);
        } else if side[i] > 0.0 {
            po[i] = po[i].next_up();
        } else if side[i] < 0.0 {
            po[i] = po[i].next_down();
        }
    }
    po
}

impl Surface {
    /// A ray leaving the surface in direction `dir`, from the side `dir` points to.
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        Ray {
            origin: offset_ray_origin(self.p, self.p_error, self.ng, dir),
            dir,
        }
    }

    /// The reflection ray of `incoming` (SPEC: offset to the side the ray came from).
    pub fn reflection_ray(&self, incoming: Vec3) -> Ray {
        let d = incoming.normalize();
        let r = (d - 2.0 * d.dot(self.n) * self.n).normalize();
        Ray {
            origin: offset_ray_origin_towards(self.p, self.p_error, self.ng, self.ng),
            dir: r,
        }
    }

    /// The pass-through ray of `incoming`: same direction, offset forward.
    pub fn pass_through_ray(&self, incoming: Vec3) -> Ray {
        self.spawn_ray(incoming)
    }

    /// A shadow ray from the viewer's side of the surface to `target`; trace it over
    /// `(0, 1 - SHADOW_EPSILON)`.
    pub fn shadow_ray_to(&self, target: Vec3) -> Ray {
        let origin = offset_ray_origin(self.p, self.p_error, self.ng, self.ng);
        Ray {
            origin,
            dir: target - origin,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_least_offset_coordinate_is_two_to_the_minus_100() {
        assert_eq!(MIN_OFFSET_COORDINATE, 2f32.powi(-100));
        assert!(MIN_OFFSET_COORDINATE.is_normal());
    }

    #[test]
    fn an_origin_leaving_a_plane_through_zero_is_off_it_and_not_subnormal() {
        // A point of the floor y = 0 with no rounding error: the origin must leave the
        // plane on the normal's side, by a normal float, in either direction.
        for (ng, w, y) in [
            (Vec3::Y, Vec3::Y, MIN_OFFSET_COORDINATE),
            (Vec3::Y, -Vec3::Y, -MIN_OFFSET_COORDINATE),
            (-Vec3::Y, Vec3::Y, MIN_OFFSET_COORDINATE),
        ] {
            let o = offset_ray_origin(Vec3::new(0.3, 0.0, -0.7), Vec3::ZERO, ng, w);
            assert_eq!(o, Vec3::new(0.3, y, -0.7));
            assert!(o.y.is_normal());
        }
        // A subnormal coordinate is moved past the least offset, away from the surface.
        let o = offset_ray_origin(Vec3::new(0.0, 1e-40, 0.0), Vec3::ZERO, Vec3::Y, Vec3::Y);
        assert_eq!(o.y, MIN_OFFSET_COORDINATE);
    }

    #[test]
    fn an_origin_off_a_plane_away_from_zero_moves_by_one_float() {
        let o = offset_ray_origin(Vec3::new(0.0, 2.0, 0.5), Vec3::ZERO, -Vec3::Y, -Vec3::Y);
        assert_eq!(o, Vec3::new(0.0, 2.0f32.next_down(), 0.5));
    }
}
