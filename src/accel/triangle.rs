//! Watertight ray/triangle intersection following Sven Woop, Carsten Benthin
//! and Ingo Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013.
//!
//! The ray is transformed so that it runs along +z from the origin (permute
//! the axes so the largest |dir| component is z, then shear x and y). The
//! triangle's 2D edge functions about the origin then decide the hit. Edges
//! shared by two triangles produce the same edge function value with opposite
//! sign in both, so a ray can never slip between them; an exactly-zero edge
//! function is recomputed in f64 so that its sign is exact.

use glam::Vec3;

use super::Ray;

/// A ray/triangle hit: parameter `t` and the barycentric weights of v0, v1, v2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit, in units of `ray.dir`.
    pub t: f32,
    /// Weight of v0.
    pub b0: f32,
    /// Weight of v1.
    pub b1: f32,
    /// Weight of v2.
    pub b2: f32,
}

/// Per-ray constants of the watertight test: axis permutation and shear.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayShear {
    /// Permuted axes; `kz` is the dominant direction axis. (`Axis`, not `usize`: an
    /// array indexed by one needs no bounds check.)
    pub kx: Axis,
    /// Second permuted axis.
    pub ky: Axis,
    /// Dominant axis of the direction.
    pub kz: Axis,
    /// Shear of x: `dir[kx] / dir[kz]`.
    pub sx: f32,
    /// Shear of y: `dir[ky] / dir[kz]`.
    pub sy: f32,
    /// Scale of z: `1 / dir[kz]`.
    pub sz: f32,
    /// The ray's direction, for the f64 recheck of hits near t = 0.
    pub dir: Vec3,
}

impl RayShear {
    /// `kx`, `ky`, `kz` as indices (each `Axis` read alone: no bounds checks).
    #[inline(always)]
    pub fn indices(&self) -> [usize; 3] {
        [self.kx as usize, self.ky as usize, self.kz as usize]
    }

    /// Precomputes the permutation and shear for `ray` (once per ray).
    pub fn new(ray: &Ray) -> RayShear {
        RayShear::with_scale(ray, |dz, _| 1.0 / dz)
    }

    /// [`RayShear::new`] for a ray whose inverse direction `inv` (`ray.dir.recip()`, as
    /// the box test needs it) is at hand: `sz` is `inv[kz]`, the same division, not
    /// done twice.
    #[inline(always)]
    pub(super) fn with_inverse(ray: &Ray, inv: [f32; 3]) -> RayShear {
        RayShear::with_scale(ray, |_, kz| inv[kz])
    }

    /// The permutation and shear, with `sz` from `scale(dir[kz], kz)`.
    #[inline(always)]
    fn with_scale(ray: &Ray, scale: impl FnOnce(f32, usize) -> f32) -> RayShear {
        let a = ray.dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            Axis::X
        } else if a.y >= a.z {
            Axis::Y
        } else {
            Axis::Z
        };
        // The direction in place (the ray's memory), indexed without glam's
        // per-component `match` (a chain of branches) and without a copy of it on the
        // stack to index.
        let d: &[f32; 3] = ray.dir.as_ref();
        let dz = d[kz as usize];
        // x and y follow z cyclically, swapped when dir[kz] is negative so that the
        // winding (sign of the edge functions) stays consistent with the original
        // orientation when looking down -z: a table of the six cases, where `(kz + 1) %
        // 3` and the swap were a chain of compares and conditional moves.
        // (`Axis` entries: no bounds checks, where `usize` ones took two per ray.)
        let [kx, ky] = AXES[kz as usize][(dz < 0.0) as usize];
        RayShear {
            kx,
            ky,
            kz,
            sx: d[kx as usize] / dz,
            sy: d[ky as usize] / dz,
            sz: scale(dz, kz as usize),
            dir: ray.dir,
        }
    }
}

/// `[kx, ky]` of `RayShear` for the dominant axis `kz`: `[kz][0]` the next two axes
/// cyclically, `[kz][1]` (a negative `dir[kz]`) the same swapped.
const AXES: [[[Axis; 2]; 2]; 3] = {
    use Axis::{X, Y, Z};
    [[[Y, Z], [Z, Y]], [[Z, X], [X, Z]], [[X, Y], [Y, X]]]
};

/// An axis index (0, 1, 2) as a type of three values: an array of three indexed by
/// one (`axis as usize`) needs no bounds check, where a `usize` read from memory (a
/// table, a ray's constants) took a compare and a branch per index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Axis {
    /// x, index 0.
    X = 0,
    /// y, index 1.
    Y = 1,
    /// z, index 2.
    Z = 2,
}

impl Axis {
    /// The axis of index `k` (below 3; z for any larger).
    #[inline(always)]
    pub fn of(k: usize) -> Axis {
        match k {
            0 => Axis::X,
            1 => Axis::Y,
            _ => Axis::Z,
        }
    }
}

/// Watertight ray/triangle test; hits both windings with `t` in (0, t_max).
pub fn intersect_triangle(
    ray: &Ray,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    t_max: f32,
) -> Option<TriangleHit> {
    intersect_triangle_sheared(&RayShear::new(ray), ray.origin, v0, v1, v2, t_max)
}

/// Watertight ray/triangle test with the per-ray shear precomputed.
#[inline(always)]
pub fn intersect_triangle_sheared(
    s: &RayShear,
    ray_origin: Vec3,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    t_max: f32,
) -> Option<TriangleHit> {
    intersect_triangle_flagged(s, ray_origin, [v0, v1, v2], t_max, true)
}

/// [`intersect_triangle_sheared`] that skips its exact test for a zero-area triangle
/// unless `may_be_degenerate`: for callers that decided [`is_degenerate`] once, when
/// they stored the triangle, instead of per ray. The same answer when that is right.
#[inline(always)]
pub(super) fn intersect_triangle_flagged(
    s: &RayShear,
    ray_origin: Vec3,
    [v0, v1, v2]: [Vec3; 3],
    t_max: f32,
    may_be_degenerate: bool,
) -> Option<TriangleHit> {
    // Arrays index without glam's per-component `match`.
    let a = (v0 - ray_origin).to_array();
    let b = (v1 - ray_origin).to_array();
    let c = (v2 - ray_origin).to_array();
    let [kx, ky, kz] = s.indices();

    // Shear and scale the vertices into ray space (x and y only for now).
    let ax = a[kx] - s.sx * a[kz];
    let ay = a[ky] - s.sy * a[kz];
    let bx = b[kx] - s.sx * b[kz];
    let by = b[ky] - s.sy * b[kz];
    let cx = c[kx] - s.sx * c[kz];
    let cy = c[ky] - s.sy * c[kz];

    // Scaled barycentric coordinates: 2D edge functions about the origin.
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;

    // A zero edge function means the ray passes (to f32 precision) through an
    // edge; f64 products of the f32 inputs are exact, so the sign is exact and
    // both triangles sharing the edge agree on it.
    if u == 0.0 || v == 0.0 || w == 0.0 {
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }

    // Outside if the signs differ (both windings accepted).
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        // Degenerate projection: the ray is in the triangle's plane, or the
        // triangle has no area.
        return None;
    }

    // Scaled hit distance; compared against det-scaled bounds to defer the division.
    let az = s.sz * a[kz];
    let bz = s.sz * b[kz];
    let cz = s.sz * c[kz];
    let t_scaled = u * az + v * bz + w * cz;
    if det < 0.0 {
        if t_scaled >= 0.0 || t_scaled <= t_max * det {
            return None;
        }
    } else if t_scaled <= 0.0 || t_scaled >= t_max * det {
        return None;
    }

    // Zero-area triangles can leave a rounding-sized det after shearing;
    // reject them exactly (f64 differences and products of f32 are exact, so
    // the cross product is zero only for exactly collinear vertices).
    if may_be_degenerate && is_degenerate(v0, v1, v2) {
        return None;
    }

    let inv_det = 1.0 / det;
    let mut t = t_scaled * inv_det;
    // The division can round onto the bounds; also rejects NaN from a zero ray.
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    // A t within its own rounding error of 0 may be the surface the ray starts on: when
    // the spawn point is exact along the normal (a plane at z = 0) its offset is zero, and
    // a grazing ray from it would otherwise re-hit its own triangle. The bound follows
    // pbrt (3rd ed., 3.9.6) but carries each vertex's own magnitudes through the shear
    // (pbrt's bounds every sheared y by the largest z), so that a ray grazing a surface
    // from even a few ulps away still hits it.
    let widen = |v: [f32; 3]| v.map(f64::from);
    let bound = t_error(
        s,
        [a, b, c].map(widen),
        [ax, ay, bx, by, cx, cy].map(f64::from),
        widen([u, v, w]),
        widen([az, bz, cz]),
        f64::from(t),
        f64::from(inv_det),
        F32_UNIT_ROUNDOFF,
    );
    if f64::from(t) <= 3.0 * bound {
        // That bound is first order in the vertices' distance from the origin and can
        // exceed the true t many times over: a long thin triangle seen at a grazing angle
        // from an origin near it (Sponza's floor trim in the anchors bench, hit at t =
        // 0.003 with a bound of 0.004). Decide again in f64, whose bound is 2^29 times
        // smaller, so that only a t within f64 rounding of 0 is lost.
        t = t_in_f64(s, ray_origin, [v0, v1, v2]).map(|t| t as f32)?;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
    }
    Some(TriangleHit {
        t,
        b0: u * inv_det,
        b1: v * inv_det,
        b2: w * inv_det,
    })
}

/// Unit roundoff of f32 (round to nearest), as f64.
const F32_UNIT_ROUNDOFF: f64 = f32::EPSILON as f64 * 0.5;

/// PBRT's gamma(n) for unit roundoff `unit`: bound on the relative error of n chained
/// operations.
fn gamma_for(n: u32, unit: f64) -> f64 {
    n as f64 * unit / (1.0 - n as f64 * unit)
}

/// First-order bound on the rounding error of a `t` computed with unit roundoff `unit`.
///
/// `rel` are the vertices relative to the ray origin, `sheared` their sheared x and y,
/// `e` the edge functions, `z` the scaled z coordinates.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn t_error(
    s: &RayShear,
    rel: [[f64; 3]; 3],
    sheared: [f64; 6],
    e: [f64; 3],
    z: [f64; 3],
    t: f64,
    inv_det: f64,
    unit: f64,
) -> f64 {
    let gamma = |n| gamma_for(n, unit);
    let [ax, ay, bx, by, cx, cy] = sheared.map(f64::abs);
    let [kx, ky, kz] = s.indices();
    let (sx, sy) = (
        f64::from(s.dir[kx]) / f64::from(s.dir[kz]),
        f64::from(s.dir[ky]) / f64::from(s.dir[kz]),
    );
    // Errors of the sheared coordinates: the subtraction from the origin, the shear product, the difference.
    let ex = rel.map(|p| gamma(5) * (p[kx].abs() + (sx * p[kz]).abs()));
    let ey = rel.map(|p| gamma(5) * (p[ky].abs() + (sy * p[kz]).abs()));
    let g2 = gamma(2);
    // Errors of the edge functions u = cx by - cy bx, v = ax cy - ay cx, w = bx ay - by ax.
    let eu = cx * ey[1] + by * ex[2] + cy * ex[1] + bx * ey[2] + g2 * (cx * by + cy * bx);
    let ev = ax * ey[2] + cy * ex[0] + ay * ex[2] + cx * ey[0] + g2 * (ax * cy + ay * cx);
    let ew = bx * ey[0] + ay * ex[1] + by * ex[0] + ax * ey[1] + g2 * (bx * ay + by * ax);
    let [u, v, w] = e.map(f64::abs);
    let [az, bz, cz] = z.map(f64::abs);
    let e_det = eu + ev + ew + g2 * (u + v + w);
    let e_scaled = eu * az + ev * bz + ew * cz + gamma(6) * (u * az + v * bz + w * cz);
    (e_scaled + t.abs() * e_det) * inv_det.abs() * (1.0 + g2)
}

/// The hit distance recomputed in f64 from the f32 inputs (the same shear, edge
/// functions and scaled z), or None when it lies within its f64 rounding error of 0.
#[cold]
fn t_in_f64(s: &RayShear, origin: Vec3, v: [Vec3; 3]) -> Option<f64> {
    let d = s.dir.as_dvec3().to_array();
    let [kx, ky, kz] = s.indices();
    let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    let rel = v.map(|p| (p.as_dvec3() - origin.as_dvec3()).to_array());
    let [[ax, ay], [bx, by], [cx, cy]] = rel.map(|p| [p[kx] - sx * p[kz], p[ky] - sy * p[kz]]);
    let e = [cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax];
    let inv_det = 1.0 / (e[0] + e[1] + e[2]);
    let z = rel.map(|p| sz * p[kz]);
    let t = (e[0] * z[0] + e[1] * z[1] + e[2] * z[2]) * inv_det;
    let unit = f64::EPSILON * 0.5;
    let bound = t_error(s, rel, [ax, ay, bx, by, cx, cy], e, z, t, inv_det, unit);
    (t > 3.0 * bound).then_some(t)
}

/// The hit distance [`intersect_triangle_sheared`] computes before its f64 recheck and
/// its bound on that t's rounding error (the recheck runs when t <= 3 bound), for a
/// ray that meets the triangle with no zero edge function; for tests of bounds on it.
#[cfg(test)]
pub(super) fn t_and_error(s: &RayShear, origin: Vec3, v: [Vec3; 3]) -> Option<(f32, f64)> {
    let [a, b, c] = v.map(|p| (p - origin).to_array());
    let [kx, ky, kz] = s.indices();
    let [ax, ay, bx, by, cx, cy] = [
        a[kx] - s.sx * a[kz],
        a[ky] - s.sy * a[kz],
        b[kx] - s.sx * b[kz],
        b[ky] - s.sy * b[kz],
        c[kx] - s.sx * c[kz],
        c[ky] - s.sy * c[kz],
    ];
    let e = [cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax];
    if e.contains(&0.0) || (e.iter().any(|&e| e < 0.0) && e.iter().any(|&e| e > 0.0)) {
        return None;
    }
    let inv_det = 1.0 / (e[0] + e[1] + e[2]);
    let z = [s.sz * a[kz], s.sz * b[kz], s.sz * c[kz]];
    let t = (e[0] * z[0] + e[1] * z[1] + e[2] * z[2]) * inv_det;
    let widen = |v: [f32; 3]| v.map(f64::from);
    let bound = t_error(
        s,
        [a, b, c].map(widen),
        [ax, ay, bx, by, cx, cy].map(f64::from),
        widen(e),
        widen(z),
        f64::from(t),
        f64::from(inv_det),
        F32_UNIT_ROUNDOFF,
    );
    Some((t, bound))
}

/// True when the three vertices are exactly collinear (or coincide).
#[inline(always)]
pub(super) fn is_degenerate(v0: Vec3, v1: Vec3, v2: Vec3) -> bool {
    let e1 = v1.as_dvec3() - v0.as_dvec3();
    let e2 = v2.as_dvec3() - v0.as_dvec3();
    e1.cross(e2) == glam::DVec3::ZERO
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    use crate::test_util::{Lcg, Mesh, cube, icosphere};

    const V0: Vec3 = Vec3::new(0.0, 0.0, 0.0);
    const V1: Vec3 = Vec3::new(1.0, 0.0, 0.0);
    const V2: Vec3 = Vec3::new(0.0, 1.0, 0.0);

    fn down_at(x: f32, y: f32) -> Ray {
        Ray::new(vec3(x, y, 2.0), vec3(0.0, 0.0, -1.0))
    }

    #[test]
    fn interior_hit_is_analytic() {
        let h = intersect_triangle(&down_at(0.25, 0.5), V0, V1, V2, f32::INFINITY).unwrap();
        assert_eq!(h.t, 2.0);
        assert!((h.b0 - 0.25).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6);
        assert!((h.b2 - 0.5).abs() < 1e-6);
        // Non-unit direction: t in units of dir.
        let r = Ray::new(vec3(0.25, 0.5, 2.0), vec3(0.0, 0.0, -4.0));
        let h = intersect_triangle(&r, V0, V1, V2, f32::INFINITY).unwrap();
        assert_eq!(h.t, 0.5);
    }

    #[test]
    fn both_windings_hit_with_same_weights() {
        let a = intersect_triangle(&down_at(0.2, 0.3), V0, V1, V2, 10.0).unwrap();
        let b = intersect_triangle(&down_at(0.2, 0.3), V0, V2, V1, 10.0).unwrap();
        assert_eq!(a.t, b.t);
        assert!((a.b1 - b.b2).abs() < 1e-6 && (a.b2 - b.b1).abs() < 1e-6);
        // From below as well.
        let up = Ray::new(vec3(0.2, 0.3, -1.0), vec3(0.0, 0.0, 1.0));
        assert_eq!(intersect_triangle(&up, V0, V1, V2, 10.0).unwrap().t, 1.0);
    }

    #[test]
    fn vertex_and_edge_hits() {
        let h = intersect_triangle(&down_at(1.0, 0.0), V0, V1, V2, 10.0).unwrap();
        assert_eq!((h.t, h.b0, h.b1, h.b2), (2.0, 0.0, 1.0, 0.0));
        let h = intersect_triangle(&down_at(0.0, 0.0), V0, V1, V2, 10.0).unwrap();
        assert_eq!((h.b0, h.b1, h.b2), (1.0, 0.0, 0.0));
        // Midpoint of the hypotenuse v1-v2.
        let h = intersect_triangle(&down_at(0.5, 0.5), V0, V1, V2, 10.0).unwrap();
        assert_eq!(h.b0, 0.0);
        assert!((h.b1 - 0.5).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6);
        // Just outside that edge.
        assert!(intersect_triangle(&down_at(0.5, 0.5001), V0, V1, V2, 10.0).is_none());
    }

    #[test]
    fn t_range_is_open() {
        // Behind the origin, at exactly t_max, and beyond t_max: no hit.
        let r = Ray::new(vec3(0.2, 0.2, -1.0), vec3(0.0, 0.0, -1.0));
        assert!(intersect_triangle(&r, V0, V1, V2, 10.0).is_none());
        assert!(intersect_triangle(&down_at(0.2, 0.2), V0, V1, V2, 2.0).is_none());
        assert!(intersect_triangle(&down_at(0.2, 0.2), V0, V1, V2, 1.5).is_none());
        assert!(intersect_triangle(&down_at(0.2, 0.2), V0, V1, V2, 2.0001).is_some());
        // Origin on the triangle: t = 0 is not a hit.
        let r = Ray::new(vec3(0.2, 0.2, 0.0), vec3(0.0, 0.0, 1.0));
        assert!(intersect_triangle(&r, V0, V1, V2, 10.0).is_none());
    }

    #[test]
    fn near_hits_on_long_thin_triangles_are_kept() {
        // Sponza's floor trim: a triangle 10.8 long and 0.015 wide, hit at a grazing
        // angle from 0.002 above a neighbouring surface, well inside (barycentrics 0.61,
        // 0.32, 0.07). Exact t (rational arithmetic on these f32 values) 0.0033638108;
        // the f32 computation's error is 2.6e-5 but its first-order bound 0.004, which
        // alone would drop the hit (Embree, tinybvh and obvhs all report it).
        let r = Ray::new(
            vec3(-6.630026, 15.621754, 2.423566),
            vec3(0.6863056, 0.38305056, -0.6182693),
        );
        let (a, b, c) = (
            vec3(-10.812759, 15.61831, 2.421486),
            vec3(0.00724, 15.633309, 2.421487),
            vec3(0.00724, 15.61831, 2.421487),
        );
        let h = intersect_triangle(&r, a, b, c, f32::INFINITY).expect("a hit at t = 0.00336");
        assert!((h.t - 0.003_363_810_8).abs() < 1e-8, "t = {}", h.t);
        // Still open at t = 0: from an origin exactly on such a triangle (in the plane
        // z = 0, so that f32 origins lie exactly on it), no grazing direction hits it.
        let (a, b, c) = (
            vec3(-10.812759, 0.0, 0.0),
            vec3(0.00724, 0.015, 0.0),
            Vec3::ZERO,
        );
        let mut rng = Lcg(11);
        for _ in 0..10_000 {
            let w = [rng.next_f32(), rng.next_f32()];
            let o = a + w[0] * (b - a) + w[1] * (1.0 - w[0]) * (c - a);
            let d = vec3(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                1e-4 * (rng.next_f32() - 0.5),
            );
            assert!(o.z == 0.0);
            if let Some(h) = intersect_triangle(&Ray::new(o, d), a, b, c, f32::INFINITY) {
                assert!(h.t * d.length() < 1e-5, "origin {o} dir {d}: t = {}", h.t);
            }
        }
    }

    #[test]
    fn degenerate_triangles_never_hit() {
        let mut rng = Lcg(7);
        let tris = [
            // Two equal vertices.
            (
                vec3(0.0, 0.0, 0.0),
                vec3(1.0, 0.0, 0.0),
                vec3(1.0, 0.0, 0.0),
            ),
            // Collinear, not axis aligned.
            (
                vec3(0.0, 0.0, 0.0),
                vec3(1.0, 1.0, 1.0),
                vec3(3.0, 3.0, 3.0),
            ),
            (
                vec3(0.1, 0.2, 0.3),
                vec3(0.2, 0.4, 0.6),
                vec3(0.4, 0.8, 1.2),
            ),
            // All points equal.
            (
                vec3(0.5, 0.5, 0.5),
                vec3(0.5, 0.5, 0.5),
                vec3(0.5, 0.5, 0.5),
            ),
        ];
        for (a, b, c) in tris {
            for i in 0..20000 {
                // Aim at points of the degenerate segment (and at its ends).
                let s = if i % 3 == 0 {
                    (i % 2) as f32
                } else {
                    rng.next_f32()
                };
                let target = a.lerp(c, s);
                let origin = target + rng.dir() * 3.0;
                let r = Ray::new(origin, target - origin);
                assert!(intersect_triangle(&r, a, b, c, f32::INFINITY).is_none());
            }
        }
    }

    #[test]
    fn ray_in_plane_misses_without_nan() {
        let r = Ray::new(vec3(-1.0, 0.2, 0.0), vec3(1.0, 0.0, 0.0));
        assert!(intersect_triangle(&r, V0, V1, V2, f32::INFINITY).is_none());
        // Zero direction: no hit, no NaN hit.
        let r = Ray::new(vec3(0.2, 0.2, 1.0), Vec3::ZERO);
        assert!(intersect_triangle(&r, V0, V1, V2, f32::INFINITY).is_none());
    }

    #[test]
    fn random_hits_reproduce_the_hit_point() {
        let mut rng = Lcg(3);
        for _ in 0..10000 {
            let (a, b, c) = (rng.vec(), rng.vec(), rng.vec());
            let (w1, w2) = (rng.next_f32(), rng.next_f32());
            let (w1, w2) = if w1 + w2 > 1.0 {
                (1.0 - w1, 1.0 - w2)
            } else {
                (w1, w2)
            };
            let p = a + w1 * (b - a) + w2 * (c - a);
            let o = p + rng.dir() * 2.0;
            let r = Ray::new(o, p - o);
            if let Some(h) = intersect_triangle(&r, a, b, c, 10.0) {
                assert!(h.b0 >= 0.0 && h.b1 >= 0.0 && h.b2 >= 0.0);
                assert!((h.b0 + h.b1 + h.b2 - 1.0).abs() < 1e-4);
                assert!((h.t - 1.0).abs() < 1e-3, "t {}", h.t);
            }
        }
    }

    /// `AXES` names the two axes after the dominant one in cyclic order, swapped when
    /// the dominant component is negative, and `RayShear::new` picks them so (the
    /// winding every triangle test relies on).
    #[test]
    fn axes_follow_the_dominant_axis_cyclically_swapped_when_negative() {
        for kz in 0..3 {
            let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
            let axes = AXES[kz].map(|pair| pair.map(|k| k as usize));
            assert_eq!(axes, [[kx, ky], [ky, kx]], "{kz}");
            for sign in [1.0, -1.0] {
                let mut dir = Vec3::splat(0.25);
                dir[kz] = sign;
                let s = RayShear::new(&Ray::new(Vec3::ZERO, dir));
                let want = if sign < 0.0 { (ky, kx) } else { (kx, ky) };
                assert_eq!(s.indices(), [want.0, want.1, kz], "{dir}");
            }
        }
    }

    /// The shear from the inverse direction is `RayShear::new`'s, to the bit: on
    /// directions of every dominant axis and sign, with zero (both signs), tiny and huge
    /// components.
    #[test]
    fn shear_from_the_inverse_direction_is_new_bit_for_bit() {
        let mut rng = Lcg(29);
        let special = [0.0, -0.0, 1e-30, -3e-39, 7e30, -1.0];
        for i in 0..20000 {
            let mut d = rng.dir() * (0.01 + 10.0 * rng.next_f32());
            if i % 2 == 0 {
                d[i / 2 % 3] = special[i / 6 % special.len()];
            }
            let ray = Ray::new(rng.vec(), d);
            let (a, b) = (
                RayShear::new(&ray),
                RayShear::with_inverse(&ray, ray.dir.recip().to_array()),
            );
            let bits = |s: &RayShear| {
                let f = [s.sx, s.sy, s.sz].map(f32::to_bits);
                (s.kx, s.ky, s.kz, f, s.dir.to_array().map(f32::to_bits))
            };
            assert_eq!(bits(&a), bits(&b), "{ray:?}");
        }
    }

    /// Counts rays that hit no triangle of `mesh` (brute force).
    fn misses(mesh: &Mesh, rays: &[Ray]) -> usize {
        rays.iter()
            .filter(|r| {
                let s = RayShear::new(r);
                !(0..mesh.tris.len()).any(|i| {
                    let (a, b, c) = mesh.tri(i);
                    intersect_triangle_sheared(&s, r.origin, a, b, c, f32::INFINITY).is_some()
                })
            })
            .count()
    }

    /// Points exactly on shared edges (several fractions along each) and on vertices.
    fn edge_and_vertex_points(mesh: &Mesh, rng: &mut Lcg) -> Vec<Vec3> {
        let mut pts = mesh.verts.clone();
        for i in 0..mesh.tris.len() {
            let (a, b, c) = mesh.tri(i);
            for (p, q) in [(a, b), (b, c), (c, a)] {
                for f in [0.5, 0.25, rng.next_f32(), rng.next_f32()] {
                    pts.push(p.lerp(q, f));
                }
            }
        }
        pts
    }

    fn check_closed(mesh: &Mesh, centre: Vec3, seed: u64, reps: usize) {
        let mut rng = Lcg(seed);
        let pts: Vec<Vec3> = (0..reps)
            .flat_map(|_| edge_and_vertex_points(mesh, &mut rng))
            .collect();
        // From outside, along the outward radial line through the point: the
        // ray crosses the surface transversally there, so it must hit.
        let outside: Vec<Ray> = pts
            .iter()
            .map(|&p| {
                let o = centre + (p - centre) * 3.0;
                Ray::new(o, p - o)
            })
            .collect();
        // From inside (random interior points) through the same points.
        let inside: Vec<Ray> = pts
            .iter()
            .map(|&p| {
                let o = centre + (rng.vec() - Vec3::splat(0.5)) * 0.2;
                Ray::new(o, p - o)
            })
            .collect();
        // From inside in random directions.
        let random: Vec<Ray> = (0..pts.len())
            .map(|_| Ray::new(centre, rng.dir()))
            .collect();
        assert!(pts.len() > 1000, "too few test rays: {}", pts.len());
        assert_eq!(misses(mesh, &outside), 0, "outside rays slipped through");
        assert_eq!(misses(mesh, &inside), 0, "inside rays slipped through");
        assert_eq!(misses(mesh, &random), 0, "random inside rays escaped");
    }

    #[test]
    fn watertight_icosphere() {
        let mut m = icosphere(3);
        // Move it off the origin with awkward values so the arithmetic rounds.
        let off = vec3(0.3137, -1.771, 2.0913);
        for v in &mut m.verts {
            *v = *v * 1.37 + off;
        }
        check_closed(&m, off, 11, 1);
    }

    #[test]
    fn watertight_cube() {
        let min = vec3(-0.713, -1.291, 0.377);
        let max = vec3(1.119, 0.8537, 2.2211);
        let m = cube(min, max);
        // Many rays through the few edges of a cube.
        let mut rng = Lcg(5);
        let centre = (min + max) * 0.5;
        let mut rays = Vec::new();
        for _ in 0..200 {
            for p in edge_and_vertex_points(&m, &mut rng) {
                let o = centre + (rng.vec() - Vec3::splat(0.5)) * 0.5;
                rays.push(Ray::new(o, p - o));
                let o = centre + (p - centre) * (2.0 + rng.next_f32());
                rays.push(Ray::new(o, p - o));
            }
        }
        assert!(rays.len() > 10000);
        assert_eq!(misses(&m, &rays), 0);
        check_closed(&m, centre, 17, 50);
    }
}
