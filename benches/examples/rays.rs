//! Traces the anchors bench's torus ray sets (primary, incoherent, shadow)
//! through glint's 8-wide BVH once each, for `scripts/callgrind_rays.sh`,
//! which counts only the instructions inside [`trace_rays`]: building the
//! mesh, the BVH and the rays is left out of the figure.
//!   rays [TORUS_N] [RAYS]   (defaults 158, the 100k torus, and 65536 rays)
//! With `GLINT_RAYS_PACKETS` set, every set goes 8 consecutive rays at a time through
//! `WideBvh::occluded_packet` or `closest_packet_within` (as the render traces its rays).

use std::hint::black_box;

use glint::accel::{PACKET, Ray, WideBvh};
use glint_bench::{
    View, displaced_torus, glint_wide, glint_wide_hits, incoherent_rays, primary_rays, shadow_rays,
    thread_cpu_ns,
};

/// The queries the anchors bench times for glint: any-hit up to t = 1 for
/// shadow rays, closest hit without a bound otherwise; returns the hits.
#[inline(never)]
fn trace_rays(wide: &WideBvh, rays: &[Ray], shadow: bool) -> u32 {
    if std::env::var_os("GLINT_RAYS_PACKETS").is_some() {
        let t_max = [if shadow { 1.0 } else { f32::INFINITY }; PACKET];
        return rays
            .chunks(PACKET)
            .map(|c| {
                let t_max = &t_max[..c.len()];
                if shadow {
                    wide.occluded_packet(c, t_max).count_ones()
                } else {
                    // The render's entry: one bound, the hits kept in lanes.
                    wide.closest_packet_within(c, f32::INFINITY)
                        .found
                        .count_ones()
                }
            })
            .sum();
    }
    glint_wide_hits(wide, rays, shadow)
}

fn main() {
    let arg = |k: usize, default: usize| {
        std::env::args()
            .nth(k)
            .and_then(|a| a.parse().ok())
            .unwrap_or(default)
    };
    let (n, n_rays) = (arg(1, 158), arg(2, 1 << 16));
    let tris = displaced_torus(n);
    let wide = glint_wide(&tris);
    let view = View::torus();
    let side = (n_rays as f64).sqrt() as usize;
    let sets = [
        ("primary", primary_rays(&view, side, side)),
        ("incoherent", incoherent_rays(&tris, &view, n_rays)),
        ("shadow", shadow_rays(&tris, &view, n_rays)),
    ];
    for (name, rays) in &sets {
        let hits = black_box(trace_rays(&wide, rays, *name == "shadow"));
        println!("{name} {} rays {hits} hits", rays.len());
    }
    // With GLINT_RAYS_REPEAT=k: k rounds of the three sets, each round tracing each set
    // once, and each set's least and median time on the CPU, for A/B runs of builds of
    // this example on a shared machine (CPU time leaves out the time other processes
    // held the core; the least is the least disturbed by them).
    let repeat: usize = std::env::var("GLINT_RAYS_REPEAT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    if repeat > 0 {
        let mut ms = vec![Vec::new(); sets.len()];
        for _ in 0..repeat {
            for (k, (name, rays)) in sets.iter().enumerate() {
                let start = thread_cpu_ns();
                black_box(trace_rays(&wide, rays, *name == "shadow"));
                ms[k].push((thread_cpu_ns() - start) as f64 * 1e-6);
            }
        }
        for (k, (name, _)) in sets.iter().enumerate() {
            ms[k].sort_by(f64::total_cmp);
            println!(
                "time {name}: least {:.2} ms median {:.2} ms",
                ms[k][0],
                ms[k][ms[k].len() / 2]
            );
        }
    }
    println!(
        "{} triangles, {:.1} bytes/tri",
        tris.len(),
        wide.bytes() as f64 / tris.len() as f64
    );
}
