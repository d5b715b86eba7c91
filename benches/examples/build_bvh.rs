//! Times the binned-SAH build alone (of triangles, with spatial splits where boxes
//! overlap, as a render builds them), for profiling it (`valgrind --tool=callgrind`,
//! `perf record`): `cargo run --release -p glint-bench --example build_bvh -- [n|sponza] [rounds] [threads]`
//! builds over the anchors bench's torus of about `n` triangles (default 100000), or over
//! `../shared/assets`' Dabrovic Sponza as the anchors bench loads it, `rounds` times
//! (default 5) on `threads` threads (default 1) and prints the median and range of the
//! build time, the tree's SAH cost and a hash of the tree (which changes when the tree
//! does), then the median and range of its collapse to the 8-wide BVH on the same threads
//! and the wide tree's hash (nodes and leaf groups),
//! then of both together run on a worker and from the main thread (as the anchors bench);
//! each with the median of the process's minor page faults per round (Linux; fresh pages
//! the allocator had to map, which cost about as much as the work on a loaded VM) and the
//! least and median CPU time of the thread that did the work (Linux; on a machine shared
//! with other jobs the wall time counts theirs too).

use std::time::Instant;

use glint::accel::leaf::LANES;
use glint::accel::{Bvh, SplitMethod, WideBvh};
use glint_bench::{assets_dir, displaced_torus, find_file, load_model, thread_cpu_ns};

fn main() {
    let arg = |i: usize, default: usize| {
        std::env::args()
            .nth(i)
            .map_or(default, |a| a.parse().expect("a number"))
    };
    let (rounds, threads) = (arg(2, 5), arg(3, 1));
    // Before loading Sponza, whose import runs on the global pool.
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .expect("a thread pool");
    let tris = if std::env::args().nth(1).as_deref() == Some("sponza") {
        let Some(assets) = assets_dir() else {
            glint_bench::outln!("skipping sponza: ../shared/assets is absent");
            return;
        };
        match find_file(&assets.join("classic/sponza-dabrovic"), "obj").and_then(|p| load_model(&p))
        {
            Ok(tris) => tris,
            Err(e) => {
                glint_bench::outln!("skipping sponza: {e}");
                return;
            }
        }
    } else {
        let n = arg(1, 100_000);
        displaced_torus(((n / 4) as f64).sqrt().max(1.0) as usize)
    };
    // Runs `f` on a worker of the pool (from the main thread it would run there, with
    // the main thread's allocator arena); the worker's CPU time in it.
    let in_pool = |f: &mut (dyn FnMut() + Send)| {
        rayon::scope(|_| {
            let start = thread_cpu_ns();
            f();
            thread_cpu_ns() - start
        })
    };
    let mut bvh = Bvh::default();
    let (ms, faults) = time_rounds(rounds, || {
        in_pool(&mut || bvh = Bvh::build_triangles(&tris, SplitMethod::SahBinned))
    });
    glint_bench::outln!(
        "{} triangles, {threads} threads: build {ms}, {faults} page faults, {} nodes, {} leaves, SAH cost {:.3} ({:.3} counting leaves in groups of {LANES}), hash {:016x}",
        tris.len(),
        bvh.nodes.len(),
        bvh.leaf_count(),
        bvh.sah_cost(),
        group_sah_cost(&bvh),
        bvh.tree_hash()
    );
    let mut wide = WideBvh::default();
    let (ms, faults) = time_rounds(rounds, || {
        in_pool(&mut || wide = WideBvh::collapse(&bvh, &tris))
    });
    glint_bench::outln!(
        "collapse {ms}, {faults} page faults, {} wide nodes, {:.1} bytes/tri, hash {:016x}",
        wide.nodes.len(),
        wide.bytes() as f64 / tris.len() as f64,
        wide.tree_hash()
    );
    // Both steps as the anchors bench times them (each round's trees dropped in it), on
    // a worker and then from the main thread, as its one-thread and all-threads rows do.
    let pipeline =
        || WideBvh::collapse(&Bvh::build_triangles(&tris, SplitMethod::SahBinned), &tris);
    let (worker, worker_faults) = time_rounds(rounds, || in_pool(&mut || drop(pipeline())));
    let (main, main_faults) = time_rounds(rounds, || {
        let start = thread_cpu_ns();
        drop(pipeline());
        thread_cpu_ns() - start
    });
    glint_bench::outln!(
        "build + collapse: on a worker {worker}, {worker_faults} page faults; from the main thread {main}, {main_faults} page faults"
    );
}

/// [`Bvh::sah_cost`] with a leaf costing its `LANES`-triangle groups instead of its
/// triangles: what the wide BVH's leaves test.
fn group_sah_cost(bvh: &Bvh) -> f64 {
    let area = |n: &glint::accel::BvhNode| n.bounds().surface_area() as f64;
    let cost: f64 = bvh
        .nodes
        .iter()
        .map(|n| area(n) * n.count.div_ceil(LANES as u32).max(1) as f64)
        .sum();
    cost / bvh.nodes.first().map_or(1.0, area)
}

/// Runs `f` `rounds` times (it returns the CPU time it took, in ns); the median and range
/// of its wall time and the least and median of its CPU time, and the median of the
/// minor page faults each round took.
fn time_rounds(rounds: usize, mut f: impl FnMut() -> u64) -> (String, u64) {
    let (mut ms, mut cpu, mut faults) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..rounds.max(1) {
        let before = minor_faults();
        let start = Instant::now();
        cpu.push(f() as f64 / 1e6);
        ms.push(start.elapsed().as_secs_f64() * 1e3);
        faults.push(minor_faults() - before);
    }
    ms.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    faults.sort_unstable();
    let time = format!(
        "{:.1} ms median [{:.1}-{:.1}] (CPU least {:.2}, median {:.2} ms)",
        ms[ms.len() / 2],
        ms[0],
        ms[ms.len() - 1],
        cpu[0],
        cpu[cpu.len() / 2]
    );
    (time, faults[faults.len() / 2])
}

/// The process's minor page faults so far (field 10 of `/proc/self/stat`); 0 where
/// there is no such file.
fn minor_faults() -> u64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // The command name (field 2) may hold spaces; the fields after it do not.
    let after_name = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    after_name
        .split_whitespace()
        .nth(7)
        .and_then(|f| f.parse().ok())
        .unwrap_or(0)
}
