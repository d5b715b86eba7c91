//! BVH benchmarks: glint's binned-SAH BVH next to `obvhs` (PLOC + CWBVH8) on
//! the same triangles and the same rays, in the same criterion groups: two
//! procedural meshes (100k and 1M triangles) and, when `../shared/assets` is
//! present, real models loaded through glint's own importers (the Stanford
//! bunny, the Dabrovic Sponza, MetalRoughSpheresNoTextures). Build figures are
//! Mtris/s, traversal figures Mrays/s (criterion "elements" are triangles
//! resp. rays). Traversal runs on one thread.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

use criterion::{
    BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use glam::{Vec3, Vec3A, vec3};
use glint::accel::{Aabb, Bvh, Ray, RayShear, SplitMethod, intersect_triangle_sheared};
use glint::test_util::Lcg;
use obvhs::BvhBuildParams;
use obvhs::cwbvh::{CwBvh, builder::build_cwbvh_from_tris};
use obvhs::ray::{Ray as ORay, RayHit};
use obvhs::triangle::Triangle;

/// A lat-long sphere of `n × n` quads, displaced by a few sines and a little
/// per-vertex noise, so that it has detail at several scales. Pole triangles
/// that would be degenerate are left out.
fn displaced_sphere(n: usize) -> Vec<[Vec3; 3]> {
    let mut rng = Lcg(12345);
    let cols = n;
    let rows = n;
    let mut verts = Vec::with_capacity((rows + 1) * cols);
    for i in 0..=rows {
        let theta = std::f32::consts::PI * i as f32 / rows as f32;
        for j in 0..cols {
            let phi = std::f32::consts::TAU * j as f32 / cols as f32;
            let r = 1.0
                + 0.08 * (9.0 * theta).sin() * (7.0 * phi).cos()
                + 0.03 * (31.0 * theta + 2.0).sin() * (29.0 * phi).sin()
                + 0.004 * (rng.next_f32() - 0.5);
            verts.push(
                r * vec3(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ),
            );
        }
    }
    let at = |i: usize, j: usize| verts[i * cols + j % cols];
    let mut tris = Vec::with_capacity(2 * rows * cols);
    for i in 0..rows {
        for j in 0..cols {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            if i != 0 {
                tris.push([a, b, c]);
            }
            if i != rows - 1 {
                tris.push([a, c, d]);
            }
        }
    }
    tris
}

/// Where the rays come from: a camera, a point light, and how far ray origins
/// leave the surface.
struct View {
    eye: Vec3,
    target: Vec3,
    fov_y_degrees: f32,
    light: Vec3,
    offset: f32,
    /// Orient normals away from this point (the mesh is star-shaped about it);
    /// `None` keeps the winding's normal (incoherent rays pick a side anyway)
    /// and offsets shadow-ray origins towards the light.
    star_centre: Option<Vec3>,
}

impl View {
    /// The procedural sphere: seen from +z, lit from above right.
    fn sphere() -> Self {
        Self {
            eye: vec3(0.3, 0.4, 3.0),
            target: Vec3::ZERO,
            fov_y_degrees: 40.0,
            light: vec3(2.0, 3.0, 2.5),
            offset: 1e-3,
            star_centre: Some(Vec3::ZERO),
        }
    }

    /// A model: glint's automatic camera framing the bounds, and glint's
    /// default point light (above and to the left of the eye).
    fn framing(tris: &[[Vec3; 3]]) -> Self {
        let (lo, hi) = tris
            .iter()
            .flatten()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let (centre, radius) = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
        let cam = glint::scene::model::framing_camera(centre, radius, 256, 256);
        let eye = cam.position - centre;
        let up_left = vec3(-0.5, 1.0, 0.0) * eye.length();
        Self {
            eye: cam.position,
            target: cam.look_at,
            fov_y_degrees: cam.fov_y_degrees,
            light: centre + (eye + up_left) * 1.2,
            offset: 1e-4 * radius,
            star_centre: None,
        }
    }
}

/// Pinhole camera grid looking from `view.eye` at `view.target`.
fn primary_rays(view: &View, w: usize, h: usize) -> Vec<Ray> {
    let eye = view.eye;
    let fwd = (view.target - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let tan = (view.fov_y_degrees.to_radians() * 0.5).tan();
    let mut rays = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let u = ((x as f32 + 0.5) / w as f32 * 2.0 - 1.0) * tan;
            let v = (1.0 - (y as f32 + 0.5) / h as f32 * 2.0) * tan;
            rays.push(Ray::new(eye, (fwd + u * right + v * up).normalize()));
        }
    }
    rays
}

/// Random surface points (with their geometric normals).
fn surface_points(
    tris: &[[Vec3; 3]],
    n: usize,
    star_centre: Option<Vec3>,
    rng: &mut Lcg,
) -> Vec<(Vec3, Vec3)> {
    (0..n)
        .map(|_| {
            let [a, b, c] =
                tris[((rng.next_f32() * tris.len() as f32) as usize).min(tris.len() - 1)];
            let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = a + u * (b - a) + v * (c - a);
            let nrm = (b - a).cross(c - a).normalize_or_zero();
            match star_centre {
                Some(c) if nrm.dot(p - c) < 0.0 => (p, -nrm),
                _ => (p, nrm),
            }
        })
        .collect()
}

/// Random origins just off the surface (either side), random directions.
fn incoherent_rays(tris: &[[Vec3; 3]], view: &View, n: usize) -> Vec<Ray> {
    let mut rng = Lcg(777);
    surface_points(tris, n, view.star_centre, &mut rng)
        .into_iter()
        .map(|(p, nrm)| {
            let side = if rng.next_f32() < 0.5 { 1.0 } else { -1.0 };
            Ray::new(p + side * view.offset * nrm, rng.dir())
        })
        .collect()
}

/// Shadow rays from points just off the surface (outside a star-shaped mesh,
/// else on the light's side) to the point light; t in (0, 1).
fn shadow_rays(tris: &[[Vec3; 3]], view: &View, n: usize) -> Vec<Ray> {
    let light = view.light;
    let mut rng = Lcg(999);
    surface_points(tris, n, view.star_centre, &mut rng)
        .into_iter()
        .map(|(p, nrm)| {
            let nrm = match view.star_centre {
                None if nrm.dot(light - p) < 0.0 => -nrm,
                _ => nrm,
            };
            let o = p + view.offset * nrm;
            Ray::new(o, light - o)
        })
        .collect()
}

fn glint_closest(bvh: &Bvh, tris: &[[Vec3; 3]], ray: &Ray) -> Option<(u32, f32)> {
    let s = RayShear::new(ray);
    bvh.closest_hit(ray, f32::INFINITY, &mut (), |p, t_max| {
        let [a, b, c] = tris[p as usize];
        intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max).map(|h| h.t)
    })
}

fn glint_occluded(bvh: &Bvh, tris: &[[Vec3; 3]], ray: &Ray) -> bool {
    let s = RayShear::new(ray);
    bvh.any_hit(ray, 1.0, &mut (), |p| {
        let [a, b, c] = tris[p as usize];
        intersect_triangle_sheared(&s, ray.origin, a, b, c, 1.0).is_some()
    })
}

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
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
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

/// The first file in `dir` whose name ends with `.{ext}` (in name order).
fn find_file(dir: &Path, ext: &str) -> Result<PathBuf, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)))
        .collect();
    files.sort();
    files
        .into_iter()
        .next()
        .ok_or_else(|| format!("no .{ext} file in {}", dir.display()))
}

/// World-space triangles exactly as glint renders them: the model imported
/// by glint's own importer, flattened by its Prepare schedule.
fn load_model(path: &Path) -> Result<Vec<[Vec3; 3]>, String> {
    let mut renderer = glint::Renderer::from_file(path, &Default::default())
        .and_then(|mut r| r.prepare().map(|()| r))
        .map_err(|e| e.to_string())?;
    let mut geometry = renderer
        .world
        .resource_mut::<glint::trace::geometry::SceneGeometry>();
    Ok(std::mem::take(&mut geometry.tri_positions))
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
