//! Times the binned-SAH build alone, for profiling it (`valgrind --tool=callgrind`,
//! `perf record`): `cargo run --release -p glint-bench --example build_bvh -- [n] [rounds] [threads]`
//! builds over the anchors bench's torus of about `n` triangles (default 100000) `rounds` times
//! (default 5) on `threads` threads (default 1) and prints the median and range of the
//! build time, the tree's SAH cost and a hash of the tree (which changes when the tree
//! does), then the median and range of its collapse to the 8-wide BVH on the same threads.

use std::time::Instant;

use glint::accel::leaf::LANES;
use glint::accel::{Aabb, Bvh, SplitMethod, WideBvh};
use glint_bench::displaced_torus;

fn main() {
    let arg = |i: usize, default: usize| {
        std::env::args()
            .nth(i)
            .map_or(default, |a| a.parse().expect("a number"))
    };
    let (n, rounds, threads) = (arg(1, 100_000), arg(2, 5), arg(3, 1));
    let tris = displaced_torus(((n / 4) as f64).sqrt().max(1.0) as usize);
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    let mut ms = Vec::new();
    let mut bvh = Bvh::default();
    for _ in 0..rounds {
        let start = Instant::now();
        bvh = pool.install(|| Bvh::build(&bounds, SplitMethod::SahBinned));
        ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    ms.sort_by(f64::total_cmp);
    println!(
        "{} triangles, {threads} threads: build {:.1} ms median [{:.1}-{:.1}], {} nodes, {} leaves, SAH cost {:.3} ({:.3} counting leaves in groups of {LANES}), hash {:016x}",
        tris.len(),
        ms[ms.len() / 2],
        ms[0],
        ms[ms.len() - 1],
        bvh.nodes.len(),
        bvh.leaf_count(),
        bvh.sah_cost(),
        group_sah_cost(&bvh),
        bvh.tree_hash()
    );
    let mut ms = Vec::new();
    let mut wide = WideBvh::default();
    for _ in 0..rounds {
        let start = Instant::now();
        wide = pool.install(|| WideBvh::collapse(&bvh, &tris));
        ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    ms.sort_by(f64::total_cmp);
    println!(
        "collapse {:.1} ms median [{:.1}-{:.1}], {} wide nodes, {:.1} bytes/tri",
        ms[ms.len() / 2],
        ms[0],
        ms[ms.len() - 1],
        wide.nodes.len(),
        wide.bytes() as f64 / tris.len() as f64
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
