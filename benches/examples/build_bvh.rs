//! Times the binned-SAH build alone, for profiling it (`valgrind --tool=callgrind`,
//! `perf record`): `cargo run --release --example build_bvh -- [n] [rounds] [threads]`
//! builds over a bumpy torus of about `n` triangles (default 100000) `rounds` times
//! (default 5) on `threads` threads (default 1) and prints the median and range of the
//! build time, the tree's SAH cost and a hash of the tree (which changes when the tree
//! does).

use std::f32::consts::TAU;
use std::hash::{Hash, Hasher};
use std::time::Instant;

use glam::{Vec3, vec3};
use glint::accel::{Aabb, Bvh, SplitMethod};

/// A torus with bumps on a grid of `2m x m` quads, as the anchors bench's mesh.
fn torus(n: usize) -> Vec<[Vec3; 3]> {
    let rows = ((n / 4) as f32).sqrt().max(2.0) as usize;
    let cols = 2 * rows;
    let at = |i: usize, j: usize| {
        let theta = TAU * (i % rows) as f32 / rows as f32;
        let phi = TAU * (j % cols) as f32 / cols as f32;
        let r = 0.35 + 0.04 * (7.0 * theta).sin() * (11.0 * phi).cos();
        let ring = 1.0 + r * theta.cos();
        vec3(ring * phi.cos(), r * theta.sin(), ring * phi.sin())
    };
    let mut tris = Vec::with_capacity(2 * rows * cols);
    for i in 0..rows {
        for j in 0..cols {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    tris
}

/// SAH cost with unit node and triangle costs, relative to the root's area.
fn sah_cost(bvh: &Bvh) -> f64 {
    let root = bvh.nodes[0].bounds().surface_area() as f64;
    let cost: f64 = bvh
        .nodes
        .iter()
        .map(|n| {
            let a = n.bounds().surface_area() as f64;
            if n.is_leaf() { a * n.count as f64 } else { a }
        })
        .sum();
    cost / root
}

fn tree_hash(bvh: &Bvh) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for n in &bvh.nodes {
        (
            n.min.map(f32::to_bits),
            n.max.map(f32::to_bits),
            n.offset,
            n.count,
        )
            .hash(&mut h);
    }
    bvh.prim_indices.hash(&mut h);
    h.finish()
}

fn main() {
    let arg = |i: usize, default: usize| {
        std::env::args()
            .nth(i)
            .map_or(default, |a| a.parse().expect("a number"))
    };
    let (n, rounds, threads) = (arg(1, 100_000), arg(2, 5), arg(3, 1));
    let tris = torus(n);
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
        "{} triangles, {threads} threads: build {:.1} ms median [{:.1}-{:.1}], {} nodes, SAH cost {:.3}, hash {:016x}",
        tris.len(),
        ms[ms.len() / 2],
        ms[0],
        ms[ms.len() - 1],
        bvh.nodes.len(),
        sah_cost(&bvh),
        tree_hash(&bvh)
    );
}
