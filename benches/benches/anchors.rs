//! Benchmark anchors: glint next to its peers on the same triangles and the
//! same rays, one thread, in interleaved rounds (each round times every
//! library once on the whole ray set, in rotating order, so that load on a
//! shared machine hits all of them alike). Prints, per mesh and ray set,
//! Mrays/s and the ratio glint ÷ peer as the median and the range over the
//! rounds; then build times and glint's bytes per triangle.
//!
//! glint is the 8-wide BVH the render traverses; `glint8` the same BVH traced with
//! packets of 8 consecutive rays, as the render traces them (its ratios to Embree's
//! single rays and 16-ray packets follow on a line of their own);
//! `glint-binary` is the binary
//! tree it is collapsed from; `glint-2level`, on a model whose meshes are drawn
//! several times (MetalRoughSpheresNoTextures), is what the render traverses there:
//! the 8-wide BVH of the meshes drawn once and the two-level BVH of the instances
//! (every other row traces all instances flattened into copies). Peers: `obvhs` (CWBVH, always); tinybvh's
//! BVH8_CPU (`Intersect`, `IsOccluded`; AVX2 + FMA) when build.rs could
//! compile it, see `glint_bench::tinybvh`; Embree 4 when `GLINT_EMBREE_LIB`
//! names its library (see `glint_bench::embree`; `GLINT_EMBREE_CONFIG` adds device
//! settings, e.g. `hugepages=1`), as built by default and, as `embree-robust`, with its
//! robust flag (robust traversal, no arithmetic shortcuts: what glint always does).
//! Every peer calls its library once per ray. Build times are for one thread and for the global
//! rayon pool (glint) or Embree's default thread count (Embree's, timed after every
//! mesh: see `main`); obvhs and tinybvh (compiled without its threaded builds) build on
//! one thread here. The one-thread builds are timed in interleaved rounds too, each
//! with the threads busy in it, then glint's ÷ Embree's per round; on a mesh where
//! glint's build cuts triangles (spatial splits: Sponza), `glint objects+8` is the same
//! build without them, the like of Embree's medium build.
//!
//! `GLINT_BENCH_ROUNDS` sets the number of rounds (default 7), and
//! `GLINT_BENCH_RAYS` the rays per set (default 262144).

use std::hint::black_box;
use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use glint::accel::{Bvh, PACKET, Ray, TwoLevelBvh, WideBvh};
use glint_bench::embree::{BuildQuality, Embree, EmbreeScene};
use glint_bench::tinybvh::TinyBvh8;
use glint_bench::{
    View, assets_dir, cornell_scene, displaced_torus, find_file, glint_binary, glint_closest,
    glint_occluded, glint_wide, glint_wide_objects, incoherent_rays, load_instanced, load_model,
    primary_rays, process_cpu_ns, shadow_rays,
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
    /// What the render traverses: the 8-wide BVH.
    Glint(&'a WideBvh),
    /// The binary BVH it is collapsed from (what the render traversed before).
    GlintBinary(&'a Bvh, &'a [[Vec3; 3]]),
    /// The 8-wide BVH over the meshes drawn once and the two-level BVH over the
    /// instances of the others, each ray traced through both.
    GlintInstanced(&'a WideBvh, &'a TwoLevelBvh),
    Obvhs(&'a CwBvh, &'a [Triangle]),
    Embree(&'a EmbreeScene<'a>),
    /// Embree's single rays in a scene built with `RTC_SCENE_FLAG_ROBUST` (robust
    /// traversal, no optimizations that reduce accuracy: what glint always does).
    EmbreeRobust(&'a EmbreeScene<'a>),
    /// Embree's 16-ray packets over consecutive rays of a set (what packets buy).
    Embree16(&'a EmbreeScene<'a>),
    /// The 8-wide BVH's packets of 8 consecutive rays (`WideBvh::occluded_packet`,
    /// `WideBvh::closest_packet_within`).
    Glint8(&'a WideBvh),
    TinyBvh(&'a TinyBvh8),
}

impl Peer<'_> {
    fn name(&self) -> &'static str {
        match self {
            Peer::Glint(..) => "glint",
            Peer::GlintBinary(..) => "glint-binary",
            Peer::GlintInstanced(..) => "glint-2level",
            Peer::Obvhs(..) => "obvhs",
            Peer::Embree(..) => "embree",
            Peer::EmbreeRobust(..) => "embree-robust",
            Peer::Embree16(..) => "embree16",
            Peer::Glint8(..) => "glint8",
            Peer::TinyBvh(..) => "tinybvh8",
        }
    }

    /// Hits among `rays`: any-hit queries up to t = 1 for shadow rays, closest-hit
    /// queries without a bound otherwise.
    fn trace(&self, rays: &[Ray], shadow: bool) -> u32 {
        match self {
            Peer::Glint(wide) => count_hits(
                rays,
                shadow,
                |r| wide.any_hit(r, 1.0, |_, _| true),
                |r| wide.closest_hit(r, f32::INFINITY).is_some(),
            ),
            Peer::GlintBinary(bvh, tris) => count_hits(
                rays,
                shadow,
                |r| glint_occluded(bvh, tris, r),
                |r| glint_closest(bvh, tris, r).is_some(),
            ),
            Peer::GlintInstanced(once, two) => count_hits(
                rays,
                shadow,
                |r| once.any_hit(r, 1.0, |_, _| true) || two.any_hit(r, 1.0, |_, _, _| true),
                |r| {
                    let t = once
                        .closest_hit(r, f32::INFINITY)
                        .map_or(f32::INFINITY, |h| h.1.t);
                    t < f32::INFINITY || two.closest_hit(r, t).is_some()
                },
            ),
            Peer::Obvhs(cw, tris) => {
                let ray = |r: &Ray, t_max| {
                    ORay::new(Vec3A::from(r.origin), Vec3A::from(r.dir), 0.0, t_max)
                };
                count_hits(
                    rays,
                    shadow,
                    |r| {
                        !cw.ray_traverse_miss(ray(r, 1.0), |r, id| {
                            tris[cw.primitive_indices[id] as usize].intersect(r)
                        })
                    },
                    |r| {
                        let mut hit = RayHit::none();
                        cw.ray_traverse(ray(r, f32::INFINITY), &mut hit, |r, id| {
                            tris[cw.primitive_indices[id] as usize].intersect(r)
                        })
                    },
                )
            }
            Peer::Embree(s) | Peer::EmbreeRobust(s) => count_hits(
                rays,
                shadow,
                |r| s.occluded(r, 1.0),
                |r| s.closest(r).is_some(),
            ),
            Peer::Embree16(s) => {
                let t_max = if shadow { 1.0 } else { f32::INFINITY };
                rays.chunks(16).map(|c| s.hits16(c, shadow, t_max)).sum()
            }
            Peer::Glint8(wide) if shadow => {
                let t_max = [1.0; PACKET];
                rays.chunks(PACKET)
                    .map(|c| wide.occluded_packet(c, &t_max[..c.len()]).count_ones())
                    .sum()
            }
            // The render's entry: one bound, the hits kept in lanes.
            Peer::Glint8(wide) => rays
                .chunks(PACKET)
                .map(|c| {
                    wide.closest_packet_within(c, f32::INFINITY)
                        .found
                        .count_ones()
                })
                .sum(),
            Peer::TinyBvh(b) => count_hits(
                rays,
                shadow,
                |r| b.occluded(r, 1.0),
                |r| b.closest(r).is_some(),
            ),
        }
    }
}

/// The one loop every peer's queries run in, so that the loops cost alike.
fn count_hits(
    rays: &[Ray],
    shadow: bool,
    occluded: impl Fn(&Ray) -> bool,
    closest: impl Fn(&Ray) -> bool,
) -> u32 {
    rays.iter()
        .map(|r| if shadow { occluded(r) } else { closest(r) } as u32)
        .sum()
}

/// A timed build: its row's label and the build.
type Build<'a> = (&'static str, Box<dyn FnMut() + 'a>);

/// Each of `builds` timed once per round, the order rotating from round to round (as
/// the ray sets' rounds): a slow phase of a shared machine then falls on all of them,
/// where a build's rounds timed one after the other fell on it alone. (glint's rounds
/// still come in slow phases on a shared VM: see docs/benchmarks.md, twentieth and
/// twenty-first sessions, and `scripts/callgrind_build.sh` for counts that do not.) Per
/// build, its times in ms, round by round, and the process's CPU time over wall time in
/// them (the threads busy).
fn interleaved_ms(rounds: usize, builds: &mut [Build]) -> Vec<(Vec<f64>, f64)> {
    let mut out = vec![(Vec::new(), 0.0); builds.len()];
    let mut cpu = vec![0.0; builds.len()];
    for r in 0..rounds {
        for k in 0..builds.len() {
            let i = (r + k) % builds.len();
            let ((_, build), before, t) = (&mut builds[i], process_cpu_ns(), Instant::now());
            build();
            out[i].0.push(t.elapsed().as_secs_f64() * 1e3);
            cpu[i] += (process_cpu_ns() - before) as f64 / 1e6;
        }
    }
    for (o, cpu) in out.iter_mut().zip(cpu) {
        o.1 = cpu / o.0.iter().sum::<f64>();
    }
    out
}

/// Median, least and greatest of `v`.
fn spread(v: &[f64]) -> (f64, f64, f64) {
    let mut v = v.to_vec();
    let m = median(&mut v);
    (m, v[0], v[v.len() - 1])
}

/// Median and range of `f` over `rounds` runs, in milliseconds.
fn time_ms(rounds: usize, mut f: impl FnMut()) -> (f64, f64, f64) {
    let v: Vec<f64> = (0..rounds)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    spread(&v)
}

/// `embree`: a one-thread device (Embree's builds on all threads are timed after every
/// mesh's rows, see `main`); `two_level`:
/// how many of `tris` the render keeps flattened (the first ones) and its two-level
/// BVH over the rest, if some meshes are instanced.
fn bench_mesh(
    label: &str,
    tris: &[[Vec3; 3]],
    view: &View,
    embree: Option<&Embree>,
    two_level: Option<(usize, &TwoLevelBvh)>,
) {
    let rounds = env_usize("GLINT_BENCH_ROUNDS", 7).max(1);
    let n_rays = env_usize("GLINT_BENCH_RAYS", 1 << 18);
    let side = (n_rays as f64).sqrt() as usize;
    println!("\n== {label}: {} triangles, {rounds} rounds ==", tris.len());
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let otris: Vec<Triangle> = tris
        .iter()
        .map(|t| Triangle {
            v0: t[0].into(),
            v1: t[1].into(),
            v2: t[2].into(),
        })
        .collect();

    // Build: one thread each, then all threads where the library can; each set's
    // rounds interleaved (see `interleaved_ms`).
    let build_rounds = rounds.min(5);
    let glint_build = || glint_wide(tris);
    // Where the build cut triangles (Sponza), the same build without spatial splits:
    // the like of Embree's medium build, as glint SAH+8 is of Embree's high one.
    let cuts = glint_binary(tris).prim_indices.len() > tris.len();
    let objects = || glint_wide_objects(tris);
    let tiny = TinyBvh8::build(tris);
    let mut one: Vec<Build> = vec![
        (
            "glint SAH",
            Box::new(|| drop(black_box(one_thread.install(|| glint_binary(tris))))),
        ),
        (
            "glint SAH+8",
            Box::new(|| drop(black_box(one_thread.install(glint_build)))),
        ),
    ];
    let mut all: Vec<Build> = vec![
        (
            "glint SAH",
            Box::new(|| drop(black_box(glint_binary(tris)))),
        ),
        ("glint SAH+8", Box::new(|| drop(black_box(glint_build())))),
    ];
    if cuts {
        one.push((
            "glint objects+8",
            Box::new(|| drop(black_box(one_thread.install(objects)))),
        ));
        all.push(("glint objects+8", Box::new(|| drop(black_box(objects())))));
    }
    one.push((
        "obvhs medium",
        Box::new(|| {
            black_box(build_cwbvh_from_tris(
                &otris,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            ));
        }),
    ));
    if tiny.is_ok() {
        one.push((
            "tinybvh8",
            Box::new(|| drop(black_box(TinyBvh8::build(tris).unwrap()))),
        ));
    }
    if let Some(e1) = embree {
        one.push((
            "embree medium",
            Box::new(|| drop(black_box(e1.scene(tris).unwrap()))),
        ));
        // Embree's SBVH, the like of glint's spatial splits (which glint takes where
        // long triangles make them pay: Sponza; on the tori it builds objects alone).
        one.push((
            "embree high",
            Box::new(|| {
                drop(black_box(
                    e1.scene_with(tris, BuildQuality::High, false).unwrap(),
                ))
            }),
        ));
    }
    let one_times = interleaved_ms(build_rounds, &mut one);
    let all_times = interleaved_ms(build_rounds, &mut all);
    let labels: Vec<&str> = one.iter().map(|(label, _)| *label).collect();
    let all_labels: Vec<&str> = all.iter().map(|(label, _)| *label).collect();
    drop((one, all));
    let ms = |t: &[f64]| {
        let (m, lo, hi) = spread(t);
        format!("{m:8.1} [{lo:.1}-{hi:.1}]")
    };
    println!(
        "build, ms median [min-max], rounds interleaved: 1 thread | all {} threads; \
         threads busy on one",
        rayon::current_num_threads()
    );
    for (i, label) in labels.iter().enumerate() {
        let (times, busy) = &one_times[i];
        let many = match all_labels.iter().position(|l| l == label) {
            Some(j) => format!(" | {}", ms(&all_times[j].0)),
            None if *label == "embree medium" => " | at the end".into(),
            None => String::new(),
        };
        let note = match *label {
            "glint SAH+8" => " (binary, then collapsed to 8-wide)",
            "glint objects+8" => " (no spatial splits, as Embree medium)",
            "tinybvh8" => " (BVH8_CPU::Build)",
            "embree high" => " (spatial splits)",
            _ => "",
        };
        println!("  {label:15} {}{many} ({busy:.2} busy){note}", ms(times));
    }
    if let Err(e) = &tiny {
        println!("  skipping tinybvh: {e}");
    }
    // Per round: the two builds of each pair timed in the same round.
    let row = |label: &str| labels.iter().position(|l| *l == label);
    for (a, b) in [
        ("glint SAH+8", "embree medium"),
        ("glint objects+8", "embree medium"),
        ("glint SAH+8", "embree high"),
    ] {
        if let (Some(a), Some(b)) = (row(a), row(b)) {
            let ratios: Vec<f64> = (one_times[a].0.iter().zip(&one_times[b].0))
                .map(|(x, y)| x / y)
                .collect();
            let (m, lo, hi) = spread(&ratios);
            println!(
                "  {} ÷ {}, 1 thread, per round: {m:.2} [{lo:.2}-{hi:.2}]",
                labels[a], labels[b]
            );
        }
    }

    let bvh = glint_binary(tris);
    let wide = WideBvh::collapse(&bvh, tris);
    let per_tri = |bytes: usize| bytes as f64 / tris.len() as f64;
    let binary = size_of_val(bvh.nodes.as_slice()) + size_of_val(bvh.prim_indices.as_slice());
    let cw = build_cwbvh_from_tris(
        &otris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    );
    let embree_before = Embree::bytes_in_use();
    let escene = embree.map(|e| e.scene(tris).unwrap());
    let embree_bytes = Embree::bytes_in_use().saturating_sub(embree_before);
    println!(
        "memory, bytes/tri (positions alone {:.1}): glint 8-wide {:.1} \
         ({} nodes, depth {}; nodes + leaf-order triangles + indices), \
         glint binary {:.1} ({} nodes, {:.2}/tri; nodes + indices, positions apart)",
        per_tri(size_of_val(tris)),
        per_tri(wide.bytes()),
        wide.nodes.len(),
        wide.depth,
        per_tri(binary),
        bvh.nodes.len(),
        bvh.nodes.len() as f64 / tris.len() as f64,
    );
    let mut peer_memory = format!(
        "  obvhs {:.1} (nodes + indices; + its {}-byte triangles {:.1})",
        per_tri(size_of_val(cw.nodes.as_slice()) + size_of_val(cw.primitive_indices.as_slice())),
        size_of::<Triangle>(),
        per_tri(size_of_val(otris.as_slice())),
    );
    if let Ok(t) = &tiny {
        peer_memory += &format!(
            ", tinybvh8 {:.1} (node + triangle blocks)",
            per_tri(t.bytes())
        );
    }
    if escene.is_some() {
        peer_memory += &format!(
            ", embree {:.1} (all it holds: BVH + vertex and index buffers)",
            per_tri(embree_bytes)
        );
    }
    println!("{peer_memory}");
    let once = two_level.map(|(n, _)| WideBvh::collapse(&glint_binary(&tris[..n]), &tris[..n]));
    if let (Some(once), Some((n, two))) = (&once, two_level) {
        println!(
            "  glint-2level {:.1} per triangle drawn ({n} triangles drawn once, 8-wide; {} meshes in {} instances, two-level)",
            per_tri(once.bytes() + two.bytes()),
            two.meshes.len(),
            two.instances.len(),
        );
    }
    let mut peers = vec![
        Peer::Glint(&wide),
        Peer::Glint8(&wide),
        Peer::GlintBinary(&bvh, tris),
        Peer::Obvhs(&cw, &otris),
    ];
    if let (Some(once), Some((_, two))) = (&once, two_level) {
        peers.push(Peer::GlintInstanced(once, two));
    }
    if let Ok(t) = &tiny {
        peers.push(Peer::TinyBvh(t));
    }
    let robust = embree.map(|e| e.scene_with(tris, BuildQuality::Medium, true).unwrap());
    if let (Some(s), Some(r)) = (&escene, &robust) {
        peers.push(Peer::Embree(s));
        peers.push(Peer::EmbreeRobust(r));
        peers.push(Peer::Embree16(s));
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
        // The packets next to Embree's single rays and packets.
        let glint8 = peers.iter().position(|p| matches!(p, Peer::Glint8(..)));
        if let Some(g) = glint8 {
            let mut line = String::from("  glint8 ÷");
            for (p, peer) in peers.iter().enumerate() {
                if matches!(peer, Peer::Embree(..) | Peer::Embree16(..)) {
                    let mut ratios: Vec<f64> =
                        (0..rounds).map(|r| secs[p][r] / secs[g][r]).collect();
                    line += &format!(" {} {:.2}", peer.name(), median(&mut ratios));
                }
            }
            println!("{line}");
        }
    }
}

/// Extra Embree device settings, appended to both devices' configuration strings.
const CONFIG_VAR: &str = "GLINT_EMBREE_CONFIG";

fn main() {
    // `cargo bench` passes `--bench`; a name filter picks meshes by label.
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let wanted = |label: &str| filter.as_deref().is_none_or(|f| label.contains(f));
    // Extra device settings for both Embree devices (e.g. `hugepages=1`), so that a
    // setting glint's side gets can be given to Embree too and compared.
    let extra = std::env::var(CONFIG_VAR).unwrap_or_default();
    let config = |threads: &str| {
        [threads, extra.as_str()]
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join(",")
    };
    // Embree builds on as many threads as the live device that asks for the most
    // (`getMaxNumThreads` over all devices), so a one-thread device's build runs on
    // every core while a default device lives: until December 2026 this bench kept both
    // for the whole run, and its "1 thread" Embree builds took two threads here (1.9
    // threads busy, half the time of a build alone on its one). Nor can the default
    // device live only while its own builds are timed: once it is released, a TBB
    // worker spins in `sched_yield` for the rest of the run (a core busy beside every
    // row after it). So it is made once, after every mesh's one-thread rows.
    let embree = match Embree::load(&config("threads=1")) {
        Ok(e) => Some(e),
        Err(e) => {
            println!("skipping the Embree rows: {e}");
            None
        }
    };
    let embree = embree.as_ref();
    // Each mesh benched, for Embree's builds on all threads at the end.
    let mut benched: Vec<(&str, Vec<[Vec3; 3]>)> = Vec::new();
    if wanted("torus100k") {
        let tris = displaced_torus(158);
        bench_mesh("torus100k", &tris, &View::torus(), embree, None);
        benched.push(("torus100k", tris));
    }
    if wanted("torus1M") {
        let tris = displaced_torus(500);
        bench_mesh("torus1M", &tris, &View::torus(), embree, None);
        benched.push(("torus1M", tris));
    }
    if wanted("cornell") {
        // The 34 triangles of the whole-render benchmark's scene, from its own camera:
        // how the peers compare where the render spends its time.
        match load_model(&cornell_scene()) {
            Ok(tris) => {
                bench_mesh("cornell", &tris, &View::cornell(), embree, None);
                benched.push(("cornell", tris));
            }
            Err(e) => println!("skipping cornell: {e}"),
        }
    }
    let models = [
        ("bunny", "classic/stanford-bunny", "obj"),
        ("sponza", "classic/sponza-dabrovic", "obj"),
        (
            "mrspheres",
            "khronos-gltf/MetalRoughSpheresNoTextures/glTF-Binary",
            "glb",
        ),
    ];
    match assets_dir() {
        None => println!("skipping the real models: ../shared/assets is absent"),
        Some(assets) => {
            for (label, dir, ext) in models {
                if !wanted(label) {
                    continue;
                }
                match find_file(&assets.join(dir), ext).and_then(|p| load_instanced(&p)) {
                    Ok((tris, once, two)) if !tris.is_empty() => {
                        let two = (!two.is_empty()).then_some((once, &two));
                        bench_mesh(label, &tris, &View::framing(&tris), embree, two);
                        benched.push((label, tris));
                    }
                    Ok(_) => println!("skipping {label}: no triangles"),
                    Err(e) => println!("skipping {label}: {e}"),
                }
            }
        }
    }
    if embree.is_some() {
        embree_all_threads(&config(""), &benched);
    }
}

/// Embree's build of each of `benched` on a device with `config` (its default thread
/// count), ms median [min-max] over 5 rounds.
fn embree_all_threads(config: &str, benched: &[(&str, Vec<[Vec3; 3]>)]) {
    let en = match Embree::load(config) {
        Ok(en) => en,
        Err(e) => return println!("skipping Embree's builds on all threads: {e}"),
    };
    println!(
        "\n== embree medium on all {} threads, ms median [min-max] ==",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    for (label, tris) in benched {
        let (m, lo, hi) = time_ms(5, || {
            black_box(en.scene(tris).unwrap());
        });
        println!("  {label:<10} {m:8.1} [{lo:.1}-{hi:.1}]");
    }
}
