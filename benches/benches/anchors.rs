//! Benchmark anchors: glint next to its peers on the same triangles and the
//! same rays, one thread, in interleaved rounds (each round times every
//! library once on the whole ray set, in rotating order, so that load on a
//! shared machine hits all of them alike). Prints, per mesh and ray set,
//! Mrays/s and the ratio glint ÷ peer as the median and the range over the
//! rounds; then build times and glint's bytes per triangle.
//!
//! glint is the 4-wide BVH the render traverses; `glint-binary` is the binary
//! tree it is collapsed from. Peers: `obvhs` (CWBVH, always), Embree 4 when `GLINT_EMBREE_LIB` names its
//! library (see `glint_bench::embree`). tinybvh is not a row: `tinybvh-rs`
//! compiles its C++ with `-march=native` and only exposes the BVH8_CPU
//! traversal under `cfg(target_feature = "avx2")`, which needs the whole
//! build under different RUSTFLAGS, and BVH8_CPU has no any-hit query there.
//!
//! `GLINT_BENCH_ROUNDS` sets the number of rounds (default 7), and
//! `GLINT_BENCH_RAYS` the rays per set (default 262144).

use std::hint::black_box;
use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use glint::accel::{Aabb, Bvh, Ray, SplitMethod, WideBvh};
use glint_bench::embree::{Embree, EmbreeScene};
use glint_bench::{
    View, assets_dir, displaced_torus, find_file, glint_closest, glint_occluded, incoherent_rays,
    load_model, primary_rays, shadow_rays,
};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::{CwBvh, builder::build_cwbvh_from_tris};
use obvhs::ray::{Ray as ORay, RayHit};
use obvhs::triangle::Triangle;

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One library's view of a mesh: how to trace a ray set, counting hits.
enum Peer<'a> {
    /// What the render traverses: the 4-wide BVH.
    Glint(&'a WideBvh),
    /// The binary BVH it is collapsed from (what the render traversed before).
    GlintBinary(&'a Bvh, &'a [[Vec3; 3]]),
    Obvhs(&'a CwBvh, &'a [Triangle]),
    Embree(&'a EmbreeScene<'a>),
}

impl Peer<'_> {
    fn name(&self) -> &'static str {
        match self {
            Peer::Glint(..) => "glint",
            Peer::GlintBinary(..) => "glint-binary",
            Peer::Obvhs(..) => "obvhs",
            Peer::Embree(..) => "embree",
        }
    }

    fn trace(&self, rays: &[Ray], shadow: bool) -> u32 {
        let mut hits = 0u32;
        match self {
            Peer::Glint(wide) => {
                for r in rays {
                    hits += if shadow {
                        wide.any_hit(r, 1.0, |_, _| true) as u32
                    } else {
                        wide.closest_hit(r, f32::INFINITY).is_some() as u32
                    };
                }
            }
            Peer::GlintBinary(bvh, tris) => {
                for r in rays {
                    hits += if shadow {
                        glint_occluded(bvh, tris, r) as u32
                    } else {
                        glint_closest(bvh, tris, r).is_some() as u32
                    };
                }
            }
            Peer::Obvhs(cw, tris) => {
                for r in rays {
                    let t_max = if shadow { 1.0 } else { f32::INFINITY };
                    let o = ORay::new(Vec3A::from(r.origin), Vec3A::from(r.dir), 0.0, t_max);
                    hits += if shadow {
                        !cw.ray_traverse_miss(o, |r, id| {
                            tris[cw.primitive_indices[id] as usize].intersect(r)
                        }) as u32
                    } else {
                        let mut hit = RayHit::none();
                        cw.ray_traverse(o, &mut hit, |r, id| {
                            tris[cw.primitive_indices[id] as usize].intersect(r)
                        }) as u32
                    };
                }
            }
            Peer::Embree(s) => {
                for r in rays {
                    hits += if shadow {
                        s.occluded(r, 1.0) as u32
                    } else {
                        s.closest(r).is_some() as u32
                    };
                }
            }
        }
        hits
    }
}

/// Median and range of `f` over `rounds` runs, in milliseconds.
fn time_ms(rounds: usize, mut f: impl FnMut()) -> (f64, f64, f64) {
    let mut v: Vec<f64> = (0..rounds)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    let m = median(&mut v);
    (m, v[0], v[v.len() - 1])
}

fn bench_mesh(label: &str, tris: &[[Vec3; 3]], view: &View, embree: Option<&Embree>) {
    let rounds = env_usize("GLINT_BENCH_ROUNDS", 7).max(1);
    let n_rays = env_usize("GLINT_BENCH_RAYS", 1 << 18);
    let side = (n_rays as f64).sqrt() as usize;
    println!("\n== {label}: {} triangles, {rounds} rounds ==", tris.len());
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let otris: Vec<Triangle> = tris
        .iter()
        .map(|t| Triangle {
            v0: t[0].into(),
            v1: t[1].into(),
            v2: t[2].into(),
        })
        .collect();

    // Build, one thread each.
    let build_rounds = rounds.min(5);
    let (g, glo, ghi) = time_ms(build_rounds, || {
        black_box(one_thread.install(|| Bvh::build(&bounds, SplitMethod::SahBinned)));
    });
    let (w, wlo, whi) = time_ms(build_rounds, || {
        black_box(
            one_thread
                .install(|| WideBvh::collapse(&Bvh::build(&bounds, SplitMethod::SahBinned), tris)),
        );
    });
    let (o, olo, ohi) = time_ms(build_rounds, || {
        black_box(build_cwbvh_from_tris(
            &otris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        ));
    });
    println!("build (1 thread, ms, median [min-max]):");
    println!("  glint SAH     {g:9.1} [{glo:.1}-{ghi:.1}]");
    println!("  glint SAH+4   {w:9.1} [{wlo:.1}-{whi:.1}] (binary, then collapsed to 4-wide)");
    println!("  obvhs medium  {o:9.1} [{olo:.1}-{ohi:.1}]");
    if let Some(e) = embree {
        let (m, lo, hi) = time_ms(build_rounds, || {
            black_box(e.scene(tris).unwrap());
        });
        println!("  embree medium {m:9.1} [{lo:.1}-{hi:.1}]");
    }

    let bvh = Bvh::build(&bounds, SplitMethod::SahBinned);
    let wide = WideBvh::collapse(&bvh, tris);
    let per_tri = |bytes: usize| bytes as f64 / tris.len() as f64;
    let binary = size_of_val(bvh.nodes.as_slice()) + size_of_val(bvh.prim_indices.as_slice());
    println!(
        "glint memory, bytes/tri: binary {} nodes ({:.2}/tri) + indices {:.1}; \
         4-wide {} nodes, depth {}, + leaf-order triangles + indices {:.1}; positions {:.1}",
        bvh.nodes.len(),
        bvh.nodes.len() as f64 / tris.len() as f64,
        per_tri(binary),
        wide.nodes.len(),
        wide.depth,
        per_tri(wide.bytes()),
        per_tri(size_of_val(tris)),
    );
    let cw = build_cwbvh_from_tris(
        &otris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    );
    let escene = embree.map(|e| e.scene(tris).unwrap());
    let mut peers = vec![
        Peer::Glint(&wide),
        Peer::GlintBinary(&bvh, tris),
        Peer::Obvhs(&cw, &otris),
    ];
    if let Some(s) = &escene {
        peers.push(Peer::Embree(s));
    }

    let ray_sets: [(&str, Vec<Ray>); 3] = [
        ("primary", primary_rays(view, side, side)),
        ("incoherent", incoherent_rays(tris, view, n_rays)),
        ("shadow", shadow_rays(tris, view, n_rays)),
    ];
    println!("trace (1 thread): Mrays/s median, glint ÷ peer median [min-max], hits");
    for (case, rays) in &ray_sets {
        let shadow = *case == "shadow";
        // secs[peer][round]
        let mut secs = vec![Vec::with_capacity(rounds); peers.len()];
        let mut hits = vec![0; peers.len()];
        for round in 0..rounds {
            for k in 0..peers.len() {
                let p = (round + k) % peers.len();
                let t = Instant::now();
                hits[p] = black_box(peers[p].trace(rays, shadow));
                secs[p].push(t.elapsed().as_secs_f64());
            }
        }
        let mrays = |p: usize| rays.len() as f64 / median(&mut secs[p].clone()) / 1e6;
        let mut line = format!("  {case:<10} glint {:6.2} ({})", mrays(0), hits[0]);
        for p in 1..peers.len() {
            let mut ratios: Vec<f64> = (0..rounds).map(|r| secs[p][r] / secs[0][r]).collect();
            let m = median(&mut ratios);
            line += &format!(
                " | {} {:6.2} ({}) ratio {m:.2} [{:.2}-{:.2}]",
                peers[p].name(),
                mrays(p),
                hits[p],
                ratios[0],
                ratios[rounds - 1]
            );
        }
        println!("{line}");
    }
}

fn main() {
    // `cargo bench` passes `--bench`; a name filter picks meshes by label.
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let wanted = |label: &str| filter.as_deref().is_none_or(|f| label.contains(f));
    let embree = match Embree::load("threads=1") {
        Ok(e) => Some(e),
        Err(e) => {
            println!("skipping the Embree rows: {e}");
            None
        }
    };
    println!(
        "skipping the tinybvh rows: tinybvh-rs needs the whole build with target-feature=+avx2 (see anchors.rs)"
    );
    let embree = embree.as_ref();
    if wanted("torus100k") {
        bench_mesh("torus100k", &displaced_torus(158), &View::torus(), embree);
    }
    if wanted("torus1M") {
        bench_mesh("torus1M", &displaced_torus(500), &View::torus(), embree);
    }
    let Some(assets) = assets_dir() else {
        println!("skipping the real models: ../shared/assets is absent");
        return;
    };
    let models = [
        ("bunny", "classic/stanford-bunny", "obj"),
        ("sponza", "classic/sponza-dabrovic", "obj"),
    ];
    for (label, dir, ext) in models {
        if !wanted(label) {
            continue;
        }
        match find_file(&assets.join(dir), ext).and_then(|p| load_model(&p)) {
            Ok(tris) if !tris.is_empty() => bench_mesh(label, &tris, &View::framing(&tris), embree),
            Ok(_) => println!("skipping {label}: no triangles"),
            Err(e) => println!("skipping {label}: {e}"),
        }
    }
}
