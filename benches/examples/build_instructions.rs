//! One one-thread build of the anchors bench's torus of about `n` triangles, by glint
//! (binary SAH build, then the collapse to 8-wide, as a render builds) or by Embree's
//! medium build, inside `measured_build` alone, for callgrind to count:
//! `scripts/callgrind_build.sh` runs it. Instructions are the same on a quiet machine and
//! a loaded one, where the build's time on this VM is not (docs/benchmarks.md,
//! twenty-first session). Each library builds once before, uncounted, so that neither
//! pays its first-call setup in the count.
//!   `cargo run --release -p glint-bench --example build_instructions -- glint|embree [n]`

use glint_bench::embree::Embree;
use glint_bench::{displaced_torus, glint_wide};

fn main() {
    let which = std::env::args().nth(1).unwrap_or_default();
    let n = std::env::args()
        .nth(2)
        .map_or(100_000, |a| a.parse().expect("a number"));
    let tris = displaced_torus(((n / 4) as f64).sqrt().max(1.0) as usize);
    match which.as_str() {
        "glint" => {
            // On a pool of one thread, as the anchors' one-thread row: every step of the
            // build then runs on its worker, inside `measured_build`.
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .expect("a thread pool");
            let build = || drop(std::hint::black_box(glint_wide(&tris)));
            pool.install(build);
            pool.install(|| measured_build(build));
        }
        "embree" => match Embree::load("threads=1") {
            Ok(e) => {
                let build = || drop(std::hint::black_box(e.scene(&tris).expect("a scene")));
                build();
                measured_build(build);
            }
            Err(e) => {
                glint_bench::outln!("skipping embree: {e}");
                return;
            }
        },
        _ => {
            eprintln!("usage: build_instructions glint|embree [n]");
            std::process::exit(2);
        }
    }
    glint_bench::outln!("{} triangles", tris.len());
}

/// Runs `build`: the function whose instructions callgrind counts.
#[inline(never)]
fn measured_build(build: impl FnOnce()) {
    build();
}
