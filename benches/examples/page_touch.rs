//! What the first write to fresh memory costs on this machine, per 2 MiB, for the BVH's
//! arrays as glint keeps them (`HugeVec`: a huge-page-advised mapping) and on the heap:
//! `cargo run --release -p glint-bench --example page_touch -- [MiB] [idle s] [rounds]`
//! (defaults 64, 3, 3). The first array of each kind is timed alone; then each round
//! takes a fresh array, writes a byte in every 4 KiB page, and drops it; "hot" rounds
//! follow one another (the pages just given back are taken again), "idle" rounds wait
//! `idle` seconds first. On a VM that reports freed memory to its host
//! (`page_reporting` in the guest kernel), idle pages were handed back and the host must
//! fault them in again: part of what a build pays there (docs/benchmarks.md, twentieth
//! and twenty-first sessions; most of the anchors' slow build rounds are something else).

use std::time::{Duration, Instant};

use glint::accel::huge::{Backing, HUGE_PAGE, HugeVec};

fn main() {
    let arg = |i: usize, default: u64| {
        std::env::args()
            .nth(i)
            .map_or(default, |a| a.parse().expect("a number"))
    };
    let (mib, idle, rounds) = (arg(1, 64) as usize, arg(2, 3), arg(3, 3) as usize);
    let bytes = mib << 20;
    let per = |t: f64| t / (bytes as f64 / HUGE_PAGE as f64);
    for (label, backing) in [("mapped", Backing::Mapped), ("heap", Backing::Heap)] {
        // The process's first array: memory it never had.
        glint_bench::outln!(
            "{label:6} first: {:.2} ms per 2 MiB",
            per(touch(bytes, backing))
        );
        for (when, pause) in [("hot", 0), ("idle", idle)] {
            // One untimed round first, so that "hot" rounds start from pages just freed.
            touch(bytes, backing);
            let mut ms: Vec<f64> = (0..rounds.max(1))
                .map(|_| {
                    std::thread::sleep(Duration::from_secs(pause));
                    touch(bytes, backing)
                })
                .collect();
            ms.sort_by(f64::total_cmp);
            glint_bench::outln!(
                "{label:6} {when:4} ({pause} s between): {:.2} ms per 2 MiB median [{:.2}-{:.2}] over {mib} MiB",
                per(ms[ms.len() / 2]),
                per(ms[0]),
                per(ms[ms.len() - 1])
            );
        }
    }
}

/// Takes a zeroed array of `bytes` kept as `backing`, writes one byte in each 4 KiB
/// page (the first touch, as a build's first pass does) and drops it: the writes' ms.
fn touch(bytes: usize, backing: Backing) -> f64 {
    let mut v = HugeVec::<u8>::zeroed(bytes, backing);
    let start = Instant::now();
    for page in v.as_mut_slice().chunks_mut(4096) {
        page[0] = 1;
    }
    let ms = start.elapsed().as_secs_f64() * 1e3;
    std::hint::black_box(&v);
    ms
}
