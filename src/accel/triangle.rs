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
use super::leaf::{clear_of_zero, error_sizes};

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
    v: [Vec3; 3],
    t_max: f32,
    may_be_degenerate: bool,
) -> Option<TriangleHit> {
    intersect_triangle_checked::<true>(s, ray_origin, v, t_max, may_be_degenerate)
}

/// [`intersect_triangle_flagged`], whose shortcut past the f64 bound on t (`SHORTCUT`)
/// tests can turn off: the answer must be the same either way.
#[inline(always)]
pub(super) fn intersect_triangle_checked<const SHORTCUT: bool>(
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
    let zero = u == 0.0 || v == 0.0 || w == 0.0;
    if zero {
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
    let hit = |t| TriangleHit {
        t,
        b0: u * inv_det,
        b1: v * inv_det,
        b2: w * inv_det,
    };
    // A t clear of its error bound as the packet leaves decide it (`clear_of_zero`,
    // without a zero edge function, as there) needs no f64 bound: Cornell direct,
    // whose shadow packets come here per occluded ray, 365 -> 357 instructions per ray.
    if SHORTCUT && !zero {
        let sizes = error_sizes(
            &[a[kz], b[kz], c[kz]],
            &[ax, ay, bx, by, cx, cy],
            s.sz.abs(),
        );
        if clear_of_zero(t, det, sizes) {
            return Some(hit(t));
        }
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
    Some(hit(t))
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
#[path = "triangle_tests.rs"]
mod tests;
