//! What sorting a ray queue before tracing buys (issue #12 part 5): each set traced
//! as generated, then sorted by direction octant and the Morton code of its origin
//! (10 bits per axis over the scene's box); prints ms per set, median of ROUNDS, for
//! the tracing as generated, the sort itself and the tracing sorted. The anchors'
//! incoherent and shadow sets start from random surface points; the pixel-order sets
//! start from the primary hits in pixel order, as a render's queues do.
//!   sort_rays [TORUS_N] [RAYS] [ROUNDS]   (defaults 158, the 100k torus; 2^18; 5)

use std::hint::black_box;
use std::time::Instant;

use glint::accel::{Aabb, Ray};
use glint_bench::{
    View, displaced_torus, glint_wide, glint_wide_hits, incoherent_rays, primary_rays, shadow_rays,
};

fn spread(v: u32) -> u64 {
    let mut x = v as u64 & 0x3ff;
    x = (x | (x << 16)) & 0x30000ff;
    x = (x | (x << 8)) & 0x300f00f;
    x = (x | (x << 4)) & 0x30c30c3;
    (x | (x << 2)) & 0x9249249
}

fn sort(rays: &[Ray], b: &Aabb) -> Vec<Ray> {
    let ext = (b.max - b.min).max(glam::Vec3::splat(1e-30));
    let mut keyed: Vec<(u64, u32)> = rays
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let q = ((r.origin - b.min) / ext * 1023.0)
                .clamp(glam::Vec3::ZERO, glam::Vec3::splat(1023.0));
            let m = spread(q.x as u32) | (spread(q.y as u32) << 1) | (spread(q.z as u32) << 2);
            let oct = (r.dir.x < 0.0) as u64
                | ((r.dir.y < 0.0) as u64) << 1
                | ((r.dir.z < 0.0) as u64) << 2;
            ((oct << 30) | m, i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.iter().map(|&(_, i)| rays[i as usize]).collect()
}

fn main() {
    let arg = |k: usize, d: usize| {
        std::env::args()
            .nth(k)
            .and_then(|a| a.parse().ok())
            .unwrap_or(d)
    };
    let (n, n_rays, rounds) = (arg(1, 158), arg(2, 1 << 18), arg(3, 5));
    let tris = displaced_torus(n);
    let wide = glint_wide(&tris);
    let view = View::torus();
    // Render-like sets: from the primary hits in pixel order, a shadow ray to the light
    // and the mirror reflection.
    let side = (n_rays as f64).sqrt() as usize;
    let (mut pix_shadow, mut pix_reflect) = (vec![], vec![]);
    for r in primary_rays(&view, side, side) {
        if let Some((p, h)) = wide.closest_hit(&r, f32::INFINITY) {
            let [a, b, c] = tris[p as usize];
            let mut n = (b - a).cross(c - a).normalize();
            if n.dot(r.dir) > 0.0 {
                n = -n;
            }
            let o = r.origin + r.dir * h.t + n * view.offset;
            pix_shadow.push(Ray::new(o, view.light - o));
            let d = r.dir - 2.0 * r.dir.dot(n) * n;
            pix_reflect.push(Ray::new(o, d));
        }
    }
    for (name, rays) in [
        ("incoherent", incoherent_rays(&tris, &view, n_rays)),
        ("shadow", shadow_rays(&tris, &view, n_rays)),
        ("pixel-order shadow", pix_shadow),
        ("pixel-order reflection", pix_reflect),
    ] {
        let shadow = name.ends_with("shadow");
        let (mut a, mut s, mut b) = (vec![], vec![], vec![]);
        for _ in 0..rounds {
            let t = Instant::now();
            let h1 = black_box(glint_wide_hits(&wide, &rays, shadow));
            a.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            let sorted = black_box(sort(&rays, &wide.bounds));
            s.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            let h2 = black_box(glint_wide_hits(&wide, &sorted, shadow));
            b.push(t.elapsed().as_secs_f64() * 1e3);
            assert_eq!(h1, h2);
        }
        let med = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        glint_bench::outln!(
            "{} tris {name}: as generated {:.1} ms, sort {:.1} ms, sorted {:.1} ms ({} rays)",
            tris.len(),
            med(&mut a),
            med(&mut s),
            med(&mut b),
            rays.len()
        );
    }
}
