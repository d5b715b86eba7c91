//! [`surface_at`] of a packet's hits at once: the shading points of flattened
//! triangles (the common case) computed one hit per SIMD lane, where one at a time each
//! paid its own square roots and divisions in a chain. Every lane does the f32
//! operations of `surface_at` in the same order (glam's `cross`, `dot`, `max` and
//! `normalize_or` written out), so each `Surface` is the scalar one, bit for bit.
//! Other hits (instanced triangles, spheres) take `surface_at` itself. The points stay
//! in lanes: they are written into the queue's block as they are.

use multiversion::multiversion;

use super::packet_hits::PacketSceneHits;
use super::surface::surface_at;
use super::surface_queue::SurfaceBlock;
use crate::accel::{PACKET, Ray, gamma};
use crate::trace::geometry::SceneGeometry;

/// One f32 per hit of a packet.
type Lanes = [f32; PACKET];

/// What a flattened triangle's shading point is made of, one hit per lane (lanes
/// without such a hit hold what an earlier packet left there, or zeros: computed and
/// not read). One per task, reused packet by packet: zeroed per packet, it cost 76
/// instructions a packet (Cornell direct: about 2 per ray).
#[derive(Default)]
pub(super) struct TriangleLanes {
    /// Vertex `k`'s coordinate `a` in `v[k][a]`.
    v: [[Lanes; 3]; 3],
    /// Vertex normals, as `v` (read only when interpolating).
    normals: [[Lanes; 3]; 3],
    /// Vertex texture coordinates, as `v`.
    texcoords: [[Lanes; 2]; 3],
    /// Barycentric weights of the hit.
    bary: [Lanes; 3],
    /// The ray's direction.
    dir: [Lanes; 3],
}

/// The fields of a `Surface` but the material, one hit per lane.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct SurfaceLanes {
    pub(super) p: [Lanes; 3],
    pub(super) p_error: [Lanes; 3],
    pub(super) ng: [Lanes; 3],
    pub(super) n: [Lanes; 3],
    pub(super) uv: [Lanes; 2],
}

/// `surface_at` of each hit of `hits` (up to [`PACKET`]) on the ray of the same lane
/// in `rays`, into lane of the same index of `out` (its hit bits: the hits), with
/// `lanes` for the triangles' lanes (overwritten where there is a hit).
pub(super) fn surfaces_at(
    geometry: &SceneGeometry,
    rays: &[Ray],
    hits: &PacketSceneHits,
    interpolate_normals: bool,
    lanes: &mut TriangleLanes,
    out: &mut SurfaceBlock,
) {
    assert!(rays.len() <= PACKET);
    let flat = &hits.flat;
    let flattened = flat.found & ((1 << rays.len()) - 1);
    // The weights whole, as the packet query kept them (lanes without a hit hold
    // junk, computed and not read).
    lanes.bary = flat.bary;
    let mut left = flattened;
    while left != 0 {
        let j = left.trailing_zeros() as usize;
        left &= left - 1;
        let i = flat.prim[j] as usize;
        for (k, p) in geometry
            .tri_wide
            .triangle_at(flat.lane[j])
            .iter()
            .enumerate()
        {
            for a in 0..3 {
                lanes.v[k][a][j] = p[a];
            }
        }
        if interpolate_normals {
            for (k, n) in geometry.tri_normals[i].iter().enumerate() {
                for a in 0..3 {
                    lanes.normals[k][a][j] = n[a];
                }
            }
        }
        for (k, t) in geometry.tri_texcoords[i].iter().enumerate() {
            lanes.texcoords[k][0][j] = t.x;
            lanes.texcoords[k][1][j] = t.y;
        }
        for a in 0..3 {
            lanes.dir[a][j] = rays[j].dir[a];
        }
        out.material[j] = geometry.tri_material[i];
    }
    out.hit = flattened;
    if flattened != 0 {
        triangle_surfaces(lanes, interpolate_normals, &mut out.lanes);
    }
    // Hits of other kinds after the flattened triangles' lanes, which are written whole.
    for &(j, h) in &hits.others {
        let surface = surface_at(geometry, &rays[j as usize], &h, interpolate_normals);
        out.set(j as usize, Some(surface));
    }
}

/// `surface_at`'s arithmetic for a flattened triangle (`triangle_point` and the turn
/// of both normals to the ray) in every lane.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn triangle_surfaces(t: &TriangleLanes, interpolate_normals: bool, s: &mut SurfaceLanes) {
    let g7 = gamma(7);
    for j in 0..PACKET {
        let b = [t.bary[0][j], t.bary[1][j], t.bary[2][j]];
        let v = |k: usize, a: usize| t.v[k][a][j];
        // p = b.x p0 + b.y p1 + b.z p2, and its bound gamma(7) (|b.x p0| + ...).
        for a in 0..3 {
            let (w0, w1, w2) = (b[0] * v(0, a), b[1] * v(1, a), b[2] * v(2, a));
            s.p[a][j] = w0 + w1 + w2;
            s.p_error[a][j] = g7 * (w0.abs() + w1.abs() + w2.abs());
        }
        // ng = (p1 - p0).cross(p2 - p0).normalize_or(Z).
        let e1 = [0, 1, 2].map(|a| v(1, a) - v(0, a));
        let e2 = [0, 1, 2].map(|a| v(2, a) - v(0, a));
        let c = [
            e1[1] * e2[2] - e2[1] * e1[2],
            e1[2] * e2[0] - e2[2] * e1[0],
            e1[0] * e2[1] - e2[0] * e1[1],
        ];
        let ng = normalize_or(c, [0.0, 0.0, 1.0]);
        // n: the clamped weights' blend of the vertex normals, normalized (or ng).
        let n = if interpolate_normals {
            let w = b.map(|x| if x > 0.0 { x } else { 0.0 });
            let m = [0, 1, 2].map(|a| {
                let nk = |k: usize| t.normals[k][a][j];
                w[0] * nk(0) + w[1] * nk(1) + w[2] * nk(2)
            });
            normalize_or(m, ng)
        } else {
            ng
        };
        for a in 0..2 {
            let tk = |k: usize| t.texcoords[k][a][j];
            s.uv[a][j] = b[0] * tk(0) + b[1] * tk(1) + b[2] * tk(2);
        }
        // Both normals to the ray's side.
        let d = [t.dir[0][j], t.dir[1][j], t.dir[2][j]];
        let ng = if dot(ng, d) > 0.0 { ng.map(|x| -x) } else { ng };
        let n = if dot(n, ng) < 0.0 { n.map(|x| -x) } else { n };
        for a in 0..3 {
            s.ng[a][j] = ng[a];
            s.n[a][j] = n[a];
        }
    }
}

/// glam's `Vec3::dot`.
#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] * b[0]) + (a[1] * b[1]) + (a[2] * b[2])
}

/// glam's `Vec3::normalize_or`: `1 / length`, kept when finite and positive.
#[inline(always)]
fn normalize_or(v: [f32; 3], fallback: [f32; 3]) -> [f32; 3] {
    let rcp = 1.0 / dot(v, v).sqrt();
    if rcp.is_finite() && rcp > 0.0 {
        v.map(|x| x * rcp)
    } else {
        fallback
    }
}

#[cfg(test)]
#[path = "surface_lanes_tests.rs"]
mod tests;
