//! Traces the anchors bench's ray sets (primary, incoherent, shadow) on the torus or
//! on Sponza through glint's 8-wide BVH once each, for `scripts/callgrind_rays.sh`,
//! which counts the instructions inside [`trace_rays`] per set and those inside
//! [`trace_build`] (the binary build and its collapse): making the mesh and the rays is
//! left out of the figures.
//!   rays [TORUS_N|sponza] [RAYS]   (defaults 158, the 100k torus, and 65536 rays)
//! `sponza` is `../shared/assets`' Dabrovic Sponza, loaded and framed as the anchors
//! bench does; without that folder the example says so and exits.
//! With `GLINT_RAYS_PACKETS` set, every set goes 8 consecutive rays at a time through
//! `WideBvh::occluded_packet` or `closest_packet_within` (as the render traces its rays).
//! With `GLINT_RAYS_EMBREE` set, Embree traces the sets instead (its default build on a
//! `threads=1` device, one `rtcIntersect1` or `rtcOccluded1` a ray, as in the anchors
//! bench; the library named by `GLINT_EMBREE_LIB`), for its instructions per ray beside
//! glint's; the build counted is still glint's.

use std::hint::black_box;

use glam::Vec3;
use glint::accel::{PACKET, Ray, WideBvh};
use glint_bench::embree::{Embree, EmbreeScene};
use glint_bench::{
    View, assets_dir, displaced_torus, find_file, glint_binary, glint_wide_hits, incoherent_rays,
    load_model, primary_rays, shadow_rays, thread_cpu_ns,
};

/// The binary build and its collapse, as `glint_bench::glint_wide`; also the binary
/// tree's SAH cost.
#[inline(never)]
fn trace_build(tris: &[[Vec3; 3]]) -> (WideBvh, f64) {
    let bvh = glint_binary(tris);
    (WideBvh::collapse(&bvh, tris), bvh.sah_cost())
}

/// What traces the ray sets.
enum Tracer<'a> {
    Glint(&'a WideBvh),
    Embree(&'a EmbreeScene<'a>),
}

/// The queries the anchors bench times: any-hit up to t = 1 for shadow rays, closest
/// hit without a bound otherwise; returns the hits.
#[inline(never)]
fn trace_rays(tracer: &Tracer, rays: &[Ray], shadow: bool) -> u32 {
    let wide = match tracer {
        Tracer::Glint(wide) => wide,
        Tracer::Embree(scene) => {
            let hit = |r: &&Ray| {
                if shadow {
                    scene.occluded(r, 1.0)
                } else {
                    scene.closest(r).is_some()
                }
            };
            return rays.iter().filter(hit).count() as u32;
        }
    };
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
    // One thread, this one: the build's parallel steps then run inside `trace_build`,
    // where callgrind collects (a worker's instructions escaped it), and its count is
    // the one-thread build's.
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build_global()
        .expect("a thread pool");
    let n_rays = arg(2, 1 << 16);
    let (tris, view) = if std::env::args().nth(1).as_deref() == Some("sponza") {
        let Some(assets) = assets_dir() else {
            glint_bench::outln!("skipping sponza: ../shared/assets is absent");
            return;
        };
        match find_file(&assets.join("classic/sponza-dabrovic"), "obj").and_then(|p| load_model(&p))
        {
            Ok(tris) if !tris.is_empty() => {
                let view = View::framing(&tris);
                (tris, view)
            }
            Ok(_) => {
                glint_bench::outln!("skipping sponza: no triangles");
                return;
            }
            Err(e) => {
                glint_bench::outln!("skipping sponza: {e}");
                return;
            }
        }
    } else {
        (displaced_torus(arg(1, 158)), View::torus())
    };
    let (wide, sah_cost) = trace_build(&tris);
    let embree = match std::env::var_os("GLINT_RAYS_EMBREE").map(|_| Embree::load("threads=1")) {
        Some(Ok(e)) => Some(e),
        Some(Err(e)) => {
            glint_bench::outln!("skipping embree: {e}");
            return;
        }
        None => None,
    };
    let scene = embree
        .as_ref()
        .map(|e| e.scene(&tris).expect("an Embree scene"));
    let tracer = match &scene {
        Some(scene) => Tracer::Embree(scene),
        None => Tracer::Glint(&wide),
    };
    let side = (n_rays as f64).sqrt() as usize;
    let sets = [
        ("primary", primary_rays(&view, side, side)),
        ("incoherent", incoherent_rays(&tris, &view, n_rays)),
        ("shadow", shadow_rays(&tris, &view, n_rays)),
    ];
    for (name, rays) in &sets {
        let hits = black_box(trace_rays(&tracer, rays, *name == "shadow"));
        glint_bench::outln!("{name} {} rays {hits} hits", rays.len());
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
                black_box(trace_rays(&tracer, rays, *name == "shadow"));
                ms[k].push((thread_cpu_ns() - start) as f64 * 1e-6);
            }
        }
        for (k, (name, _)) in sets.iter().enumerate() {
            ms[k].sort_by(f64::total_cmp);
            glint_bench::outln!(
                "time {name}: least {:.2} ms median {:.2} ms",
                ms[k][0],
                ms[k][ms[k].len() / 2]
            );
        }
    }
    glint_bench::outln!(
        "{} triangles, {:.1} bytes/tri, SAH cost {sah_cost:.3}",
        tris.len(),
        wide.bytes() as f64 / tris.len() as f64
    );
}
