//! The shading models in lanes: one light sample's contribution at [`LANES`] hits at
//! once, for `shade_lanes`. Each lane does `shade::models`' f32 operations in the same
//! order (Rust never contracts them into FMAs), so the values are the scalar ones, bit
//! for bit.

// Lane loops index several arrays by the same lane, the form the vectoriser wants.
#![allow(clippy::needless_range_loop)]

use multiversion::multiversion;

use super::surface_lanes::SurfaceLanes;
use crate::sampling::SLOT_LANES;

/// Hits shaded together.
pub(super) const LANES: usize = SLOT_LANES;

/// One f32 per lane.
pub(super) type Lanes = [f32; LANES];

/// Three coordinates, each over the lanes.
pub(super) type Lanes3 = [Lanes; 3];

/// What the model reads of the group's hits' materials and rays, in lanes (lanes
/// without a hit hold what an earlier group left there, or zeros, and are never read
/// back); their shading points it reads from the queue's block (`SurfaceLanes`).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct HitLanes {
    pub(super) kd: Lanes3,
    pub(super) w: Lanes3,
    // Read by Phong and Blinn-Phong only (left unfilled for Lambertian).
    pub(super) v: Lanes3,
    pub(super) ks: Lanes3,
    pub(super) shininess: Lanes,
}

/// The models shaded in lanes: the copies `Shading::dispatch` and `shade_hits` choose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum LaneModel {
    /// `lambertian`.
    Lambertian,
    /// `phong`.
    Phong,
    /// `blinn_phong`.
    BlinnPhong,
}

impl LaneModel {
    /// The lanes' copy of the settings' model, if there is one.
    pub(super) fn of(shading: &crate::shade::Shading) -> Option<Self> {
        use crate::scene::ShadingModel;
        match (shading.enabled, shading.model) {
            (true, ShadingModel::Lambertian) => Some(Self::Lambertian),
            (true, ShadingModel::Phong) => Some(Self::Phong),
            (true, ShadingModel::BlinnPhong) => Some(Self::BlinnPhong),
            _ => None,
        }
    }
}

/// One light sample over the lanes: where it is, what it adds (`c`), and whether it
/// adds anything (`keep`: the direction to it could be normalized, else the scalar loop
/// skips the sample, and `c` is not all zeros).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct SampleLanes {
    pub(super) position: Lanes3,
    pub(super) c: Lanes3,
    // As u32 (0 or 1), not bool: the lanes store it as one vector, bools one by one.
    pub(super) keep: [u32; LANES],
}

/// The Lambertian contribution of light sample (`position`, `color`) at each lane's hit:
/// `ShadingInput`'s `lambertian(..) * w` after `try_normalize`, operation for operation.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
pub(super) fn shade_sample(
    surface: &SurfaceLanes,
    hits: &HitLanes,
    position: &Lanes3,
    color: &Lanes3,
    out: &mut SampleLanes,
) {
    out.position = *position;
    lambertian_lanes(surface, hits, color, out);
}

/// [`shade_sample`] with the sample's position already in `out.position`: its loop,
/// inlined into its callers' clones.
#[inline(always)]
pub(super) fn lambertian_lanes(
    surface: &SurfaceLanes,
    hits: &HitLanes,
    color: &Lanes3,
    out: &mut SampleLanes,
) {
    let position = &out.position;
    for j in 0..LANES {
        let lx = position[0][j] - surface.p[0][j];
        let ly = position[1][j] - surface.p[1][j];
        let lz = position[2][j] - surface.p[2][j];
        // glam: `dot` left to right, `length_recip` = 1 / sqrt, then a multiply.
        let rcp = 1.0 / ((lx * lx) + (ly * ly) + (lz * lz)).sqrt();
        // `is_finite() && > 0` as two comparisons (NaN fails both).
        let ok = rcp > 0.0 && rcp < f32::INFINITY;
        let (lx, ly, lz) = (lx * rcp, ly * rcp, lz * rcp);
        let cos = (surface.n[0][j] * lx) + (surface.n[1][j] * ly) + (surface.n[2][j] * lz);
        // `lit` is `cos > 0`; there `cos.max(0.0)` is `cos` itself.
        let lit = cos > 0.0;
        let mut c = [0.0; 3];
        for a in 0..3 {
            let d = color[a][j] * hits.kd[a][j] * cos;
            // `&`, not `&&`: one select (the branch became two masked stores, which a
            // later whole-vector load of `c` cannot forward from).
            let d = if lit & d.is_finite() { d } else { 0.0 };
            c[a] = d * hits.w[a][j];
            out.c[a][j] = c[a];
        }
        out.keep[j] = u32::from(ok & (c[0] != 0.0 || c[1] != 0.0 || c[2] != 0.0));
    }
}

/// Phong's contribution of light sample (`position`, `color`) at each lane's hit, as
/// [`shade_sample`] for `phong`.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
pub(super) fn phong_sample(
    surface: &SurfaceLanes,
    hits: &HitLanes,
    position: &Lanes3,
    color: &Lanes3,
    out: &mut SampleLanes,
) {
    specular_sample::<false>(surface, hits, position, color, out);
}

/// Blinn-Phong's contribution, as [`phong_sample`] for `blinn_phong`.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
pub(super) fn blinn_phong_sample(
    surface: &SurfaceLanes,
    hits: &HitLanes,
    position: &Lanes3,
    color: &Lanes3,
    out: &mut SampleLanes,
) {
    specular_sample::<true>(surface, hits, position, color, out);
}

/// `phong` (or `blinn_phong` when `BLINN`) times `w` after `try_normalize`, operation
/// for operation (see `shade::models`): the lane loops first, then the `powf`s one lane
/// at a time (a call, which would stop the loops from being vectorised), then the sum.
#[inline(always)]
fn specular_sample<const BLINN: bool>(
    surface: &SurfaceLanes,
    hits: &HitLanes,
    position: &Lanes3,
    color: &Lanes3,
    out: &mut SampleLanes,
) {
    out.position = *position;
    let mut ok = [false; LANES];
    let mut lit = [false; LANES];
    let mut diffuse = Lanes3::default();
    let mut lk = Lanes3::default();
    let mut base = Lanes::default();
    for j in 0..LANES {
        let lx = position[0][j] - surface.p[0][j];
        let ly = position[1][j] - surface.p[1][j];
        let lz = position[2][j] - surface.p[2][j];
        let rcp = 1.0 / ((lx * lx) + (ly * ly) + (lz * lz)).sqrt();
        ok[j] = rcp > 0.0 && rcp < f32::INFINITY;
        let l = [lx * rcp, ly * rcp, lz * rcp];
        let n = [surface.n[0][j], surface.n[1][j], surface.n[2][j]];
        let v = [hits.v[0][j], hits.v[1][j], hits.v[2][j]];
        let cos = (n[0] * l[0]) + (n[1] * l[1]) + (n[2] * l[2]);
        // `lit` is `cos > 0`; there `cos.max(0.0)` is `cos` itself.
        lit[j] = cos > 0.0;
        for a in 0..3 {
            diffuse[a][j] = color[a][j] * hits.kd[a][j] * cos;
            lk[a][j] = color[a][j] * hits.ks[a][j];
        }
        let x = if BLINN {
            // `(l + v).normalize_or_zero()`, then `n.h`.
            let h = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
            let r = 1.0 / ((h[0] * h[0]) + (h[1] * h[1]) + (h[2] * h[2])).sqrt();
            let h = if r.is_finite() && r > 0.0 {
                [h[0] * r, h[1] * r, h[2] * r]
            } else {
                [0.0; 3]
            };
            (n[0] * h[0]) + (n[1] * h[1]) + (n[2] * h[2])
        } else {
            // `r = 2 (n.l) n - l`, then `r.v`.
            let t = 2.0 * cos;
            let r = [t * n[0] - l[0], t * n[1] - l[1], t * n[2] - l[2]];
            (r[0] * v[0]) + (r[1] * v[1]) + (r[2] * v[2])
        };
        // `specular_power`'s base.
        base[j] = if x > 0.0 { x.min(1.0) } else { 0.0 };
    }
    // `specular`: with `light * ks` all zeros the highlight is that, no `powf` (times 1,
    // the same zeros).
    let mut power = [1.0; LANES];
    for j in 0..LANES {
        if lk[0][j] != 0.0 || lk[1][j] != 0.0 || lk[2][j] != 0.0 {
            let e = hits.shininess[j];
            power[j] = base[j].powf(if e > 0.0 { e } else { 0.0 });
        }
    }
    for j in 0..LANES {
        for a in 0..3 {
            let c = diffuse[a][j] + lk[a][j] * power[j];
            let c = if lit[j] && c.is_finite() { c } else { 0.0 };
            out.c[a][j] = c * hits.w[a][j];
        }
        out.keep[j] =
            u32::from(ok[j] && (out.c[0][j] != 0.0 || out.c[1][j] != 0.0 || out.c[2][j] != 0.0));
    }
}
