//! Whole-render benchmark: `scenes/cornell_box_parallelogram_light.ron` at
//! 512×512, 16 samples per pixel, direct light only (Lambertian, no
//! reflection or transparency rays; 4 shadow samples per hit on the
//! parallelogram light), rendered through glint's library API on rayon pools
//! of 1 and 2 threads in interleaved rounds. Prints the time per render
//! (median [min-max]; the whole render and its trace passes alone), rays per
//! second and the thread scaling 1→2; then Mitsuba 3's times on the same
//! scene if `scripts/mitsuba_cornell.py` has written them to
//! `benches/results/mitsuba_cornell.txt`.
//!
//! `GLINT_BENCH_ROUNDS` (default 5), `GLINT_RENDER_SIZE` (default 512) and
//! `GLINT_RENDER_SPP` (default 16) change the work.

use std::path::Path;

use glint::{Overrides, Renderer};

/// The settings that make the scene "direct light only"; scripts/mitsuba_cornell.py
/// passes the same to the `glint` binary.
const DIRECT_ONLY: [(&str, &str); 6] = [
    ("shading_model", "lambertian"),
    ("reflections", "false"),
    ("transparency", "false"),
    ("pixel_sampling", "uniform"),
    ("sampler", "independent"),
    ("shadow_samples", "4"),
];

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn median_range(v: &mut [f64]) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0], v[v.len() - 1])
}

/// One render on the current rayon pool: (whole seconds, trace seconds, rays).
fn render_once(scene: &Path, overrides: &Overrides) -> (f64, f64, u64) {
    let mut renderer = Renderer::from_file(scene, overrides).expect("the Cornell scene loads");
    let summary = renderer.render(None, &mut |_| {}).expect("the render runs");
    (
        summary.seconds,
        summary.trace_seconds(),
        summary.stats.rays.total(),
    )
}

fn main() {
    let rounds = env_usize("GLINT_BENCH_ROUNDS", 5).max(1);
    let size = env_usize("GLINT_RENDER_SIZE", 512) as u32;
    let spp = env_usize("GLINT_RENDER_SPP", 16);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = root.join("scenes/cornell_box_parallelogram_light.ron");
    let mut set: Vec<(String, String)> = DIRECT_ONLY
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    set.push(("pixel_samples".into(), spp.to_string()));
    let overrides = Overrides {
        width: Some(size),
        height: Some(size),
        seed: None,
        set,
    };
    let threads = [1usize, 2];
    let pools: Vec<rayon::ThreadPool> = threads
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        })
        .collect();
    println!(
        "== render: {} at {size}x{size}, {spp} spp, direct light only, {rounds} rounds ==",
        scene.file_name().unwrap().to_string_lossy()
    );
    // Warm-up: page in the scene and the code once, untimed.
    pools[0].install(|| render_once(&scene, &overrides));
    // [pool][round]
    let mut whole = vec![Vec::with_capacity(rounds); pools.len()];
    let mut trace = vec![Vec::with_capacity(rounds); pools.len()];
    let mut rays = 0;
    for round in 0..rounds {
        for k in 0..pools.len() {
            let p = (round + k) % pools.len();
            let (w, t, n) = pools[p].install(|| render_once(&scene, &overrides));
            whole[p].push(w);
            trace[p].push(t);
            rays = n;
        }
    }
    println!("{rays} rays per render (camera + shadow)");
    // Scaling per round: the two renders of a round ran back to back.
    let mut scaling: Vec<f64> = (0..rounds).map(|r| whole[0][r] / whole[1][r]).collect();
    let mut medians = Vec::new();
    for (p, &n) in threads.iter().enumerate() {
        let (w, wlo, whi) = median_range(&mut whole[p]);
        let (t, tlo, thi) = median_range(&mut trace[p]);
        medians.push(w);
        println!(
            "  glint {n} thread{}: {w:.3} s [{wlo:.3}-{whi:.3}] per render, \
             trace passes {t:.3} s [{tlo:.3}-{thi:.3}], {:.2} Mrays/s",
            if n == 1 { " " } else { "s" },
            rays as f64 / t / 1e6
        );
    }
    let (s, slo, shi) = median_range(&mut scaling);
    println!(
        "  scaling 1→2 threads: {s:.2}x [{slo:.2}-{shi:.2}] (per round), {:.2}x (ratio of medians)",
        medians[0] / medians[1]
    );
    let results = Path::new(env!("CARGO_MANIFEST_DIR")).join("results/mitsuba_cornell.txt");
    match std::fs::read_to_string(&results) {
        Ok(text) => {
            println!("Mitsuba 3 (from {}):", results.display());
            for line in text.lines() {
                println!("  {line}");
            }
        }
        Err(_) => println!(
            "skipping Mitsuba 3: no {} (run scripts/mitsuba_cornell.sh)",
            results.display()
        ),
    }
}
