//! BVH benchmarks: glint's binned-SAH BVH next to `obvhs` (PLOC + CWBVH8) on
//! the same triangles and the same rays, in the same criterion groups: two
//! procedural meshes (100k and 1M triangles) and, when `../shared/assets` is
//! present, real models loaded through glint's own importers (the Stanford
//! bunny, the Dabrovic Sponza, MetalRoughSpheresNoTextures). Build figures are
//! Mtris/s, traversal figures Mrays/s (criterion "elements" are triangles
//! resp. rays). Traversal runs on one thread.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{
    BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use glam::{Vec3, Vec3A};
use glint::accel::{Bvh, Ray, SplitMethod};
use glint_bench::{
    View, displaced_sphere, find_file, glint_closest, glint_occluded, incoherent_rays, load_model,
    primary_rays, shadow_rays,
};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::{CwBvh, builder::build_cwbvh_from_tris};
use obvhs::ray::{Ray as ORay, RayHit};
use obvhs::triangle::Triangle;

fn to_oray(r: &Ray, t_max: f32) -> ORay {
    ORay::new(Vec3A::from(r.origin), Vec3A::from(r.dir), 0.0, t_max)
}

fn obvhs_closest(bvh: &CwBvh, tris: &[Triangle], ray: &ORay) -> Option<(u32, f32)> {
    let mut hit = RayHit::none();
    bvh.ray_traverse(*ray, &mut hit, |r, id| {
        tris[bvh.primitive_indices[id] as usize].intersect(r)
    })
    .then(|| (bvh.primitive_indices[hit.primitive_id as usize], hit.t))
}

fn obvhs_occluded(bvh: &CwBvh, tris: &[Triangle], ray: &ORay) -> bool {
    !bvh.ray_traverse_miss(*ray, |r, id| {
        tris[bvh.primitive_indices[id] as usize].intersect(r)
    })
}

/// Criterion settings of one mesh's groups.
struct Budget {
    samples: usize,
    build_time: Duration,
    trace_time: Duration,
}

fn bench_mesh(c: &mut Criterion, label: &str, tris: &[[Vec3; 3]], view: &View, budget: &Budget) {
    let samples = budget.samples;
    let bounds = glint_bench::triangle_boxes(tris);
    let otris: Vec<Triangle> = tris
        .iter()
        .map(|t| Triangle {
            v0: t[0].into(),
            v1: t[1].into(),
            v2: t[2].into(),
        })
        .collect();
    eprintln!("{label}: {} triangles", tris.len());
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();

    // Build.
    {
        let mut g = c.benchmark_group(format!("build/{label}"));
        g.sample_size(samples)
            .sampling_mode(SamplingMode::Flat)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(budget.build_time)
            .throughput(Throughput::Elements(tris.len() as u64));
        g.bench_function("glint_sah_rayon", |b| {
            b.iter(|| Bvh::build(black_box(&bounds), SplitMethod::SahBinned))
        });
        g.bench_function("glint_sah_1thread", |b| {
            b.iter(|| one_thread.install(|| Bvh::build(black_box(&bounds), SplitMethod::SahBinned)))
        });
        g.bench_function("glint_median_rayon", |b| {
            b.iter(|| Bvh::build(black_box(&bounds), SplitMethod::Median))
        });
        // obvhs is built without its `parallel` feature here: single-threaded.
        g.bench_function("obvhs_cwbvh_medium_1thread", |b| {
            b.iter(|| {
                build_cwbvh_from_tris(
                    black_box(&otris),
                    BvhBuildParams::medium_build(),
                    &mut Duration::default(),
                )
            })
        });
        g.bench_function("obvhs_cwbvh_fast_1thread", |b| {
            b.iter(|| {
                build_cwbvh_from_tris(
                    black_box(&otris),
                    BvhBuildParams::fast_build(),
                    &mut Duration::default(),
                )
            })
        });
        g.finish();
    }

    let bvh = Bvh::build(&bounds, SplitMethod::SahBinned);
    let cw = build_cwbvh_from_tris(
        &otris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    );
    eprintln!(
        "{label}: glint BVH {} nodes, {} leaves, depth {}; obvhs CWBVH {} nodes",
        bvh.nodes.len(),
        bvh.leaf_count(),
        bvh.depth(),
        cw.nodes.len()
    );

    let ray_sets: [(&str, Vec<Ray>); 3] = [
        ("primary", primary_rays(view, 256, 256)),
        ("incoherent", incoherent_rays(tris, view, 65536)),
        ("shadow", shadow_rays(tris, view, 65536)),
    ];
    for (case, rays) in &ray_sets {
        let shadow = *case == "shadow";
        let t_max = if shadow { 1.0 } else { f32::INFINITY };
        let orays: Vec<ORay> = rays.iter().map(|r| to_oray(r, t_max)).collect();
        // Sanity: both libraries see (almost) the same hits; the triangle
        // tests differ (watertight vs Möller-Trumbore), so edges may differ.
        // obvhs 0.4 also clamps each child box's entry t to an absolute 1e-4
        // (`cwbvh::node::EPSILON`), so on models in small units (the bunny is
        // 0.15 wide, MetalRoughSpheres 0.01) it misses hits that close to the
        // origin, mostly incoherent rays leaving the surface.
        let (gh, oh) = if shadow {
            (
                rays.iter()
                    .filter(|r| glint_occluded(&bvh, tris, r))
                    .count(),
                orays
                    .iter()
                    .filter(|r| obvhs_occluded(&cw, &otris, r))
                    .count(),
            )
        } else {
            (
                rays.iter()
                    .filter_map(|r| glint_closest(&bvh, tris, r))
                    .count(),
                orays
                    .iter()
                    .filter_map(|r| obvhs_closest(&cw, &otris, r))
                    .count(),
            )
        };
        eprintln!(
            "{label}/{case}: {} rays, hits glint {gh} obvhs {oh}",
            rays.len()
        );

        let mut g = c.benchmark_group(format!("{case}/{label}"));
        g.sample_size(samples)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(budget.trace_time)
            .throughput(Throughput::Elements(rays.len() as u64));
        g.bench_function(BenchmarkId::new("glint", label), |b| {
            b.iter(|| {
                let mut hits = 0u32;
                for r in rays {
                    hits += if shadow {
                        glint_occluded(&bvh, tris, r) as u32
                    } else {
                        glint_closest(&bvh, tris, r).is_some() as u32
                    };
                }
                hits
            })
        });
        g.bench_function(BenchmarkId::new("obvhs", label), |b| {
            b.iter(|| {
                let mut hits = 0u32;
                for r in &orays {
                    hits += if shadow {
                        obvhs_occluded(&cw, &otris, r) as u32
                    } else {
                        obvhs_closest(&cw, &otris, r).is_some() as u32
                    };
                }
                hits
            })
        });
        g.finish();
    }
}

fn bench_models(c: &mut Criterion) {
    let assets = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/assets"));
    if !assets.is_dir() {
        eprintln!(
            "skipping the real-model BVH benchmarks: {} is absent",
            assets.display()
        );
        return;
    }
    let small = Budget {
        samples: 20,
        build_time: Duration::from_secs(3),
        trace_time: Duration::from_secs(2),
    };
    let large = Budget {
        samples: 10,
        build_time: Duration::from_secs(3),
        trace_time: Duration::from_secs(2),
    };
    let models = [
        ("bunny", "classic/stanford-bunny", "obj", &small),
        ("sponza", "classic/sponza-dabrovic", "obj", &small),
        (
            "mrspheres",
            "khronos-gltf/MetalRoughSpheresNoTextures/glTF-Binary",
            "glb",
            &large,
        ),
    ];
    for (label, dir, ext, budget) in models {
        let tris = match find_file(&assets.join(dir), ext).and_then(|p| load_model(&p)) {
            Ok(tris) if !tris.is_empty() => tris,
            Ok(_) => {
                eprintln!("skipping {label}: no triangles");
                continue;
            }
            Err(e) => {
                eprintln!("skipping {label}: {e}");
                continue;
            }
        };
        bench_mesh(c, label, &tris, &View::framing(&tris), budget);
    }
}

fn benches(c: &mut Criterion) {
    let budget = |samples, build_secs| Budget {
        samples,
        build_time: Duration::from_secs(build_secs),
        trace_time: Duration::from_secs(2),
    };
    bench_mesh(
        c,
        "100k",
        &displaced_sphere(224),
        &View::sphere(),
        &budget(20, 5),
    );
    bench_mesh(
        c,
        "1M",
        &displaced_sphere(708),
        &View::sphere(),
        &budget(10, 5),
    );
    bench_models(c);
}

criterion_group!(bvh, benches);
criterion_main!(bvh);
