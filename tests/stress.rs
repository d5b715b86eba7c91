//! Every `glint stress` case as a test, at the quick budget (small images, 60k rays per
//! mesh): runs `glint stress --quick --case NAME`, which fails if any of its measurements
//! is outside its bound. The harness itself lives in the binary (`src/bin/glint/stress/`),
//! whose unit tests check the table and that every case has a test here.

use std::process::Command;

#[track_caller]
fn check(name: &str) {
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["stress", "--quick", "--case", name])
        .output()
        .unwrap();
    let table = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "stress case {name} failed:\n{table}{stderr}"
    );
    assert!(
        table.starts_with("| case | measure | value | bound | result |"),
        "no table for {name}:\n{table}{stderr}"
    );
    let rows: Vec<&str> = table.lines().skip(2).collect();
    assert!(!rows.is_empty(), "no measurement for {name}");
    for row in rows {
        assert!(row.ends_with("| pass |"), "stress case {name}: {row}");
    }
}

#[test]
fn scale() {
    check("scale");
}

#[test]
fn far() {
    check("far");
}

#[test]
fn watertight() {
    check("watertight");
}

#[test]
fn axis_grazing() {
    check("axis_grazing");
}

#[test]
fn degenerate() {
    check("degenerate");
}

#[test]
fn coincident() {
    check("coincident");
}

#[test]
fn deep_chains() {
    check("deep_chains");
}

#[test]
fn spheres() {
    check("spheres");
}

#[test]
fn lights() {
    check("lights");
}

#[test]
fn textures() {
    check("textures");
}

#[test]
fn validation() {
    check("validation");
}

/// The film drops and counts non-finite samples (the stress case `lights` checks it end
/// to end through an overflowing light; this checks the system on its own).
#[test]
fn film_counts_and_drops_nonfinite_samples() {
    use bevy_ecs::prelude::*;
    use bevy_ecs::system::RunSystemOnce;
    use glam::Vec3;
    use glint::film::{Film, accumulate_film};
    use glint::stats::RenderStats;
    use glint::trace::wavefront::{PassRegion, SampleRadiance};

    let mut world = World::new();
    world.insert_resource(Film::new(4, 1));
    world.insert_resource(RenderStats::default());
    world.insert_resource(PassRegion {
        sample: 0,
        first_pixel: 0,
        pixels: 4,
    });
    world.insert_resource(SampleRadiance {
        first_pixel: 0,
        values: vec![
            Vec3::ONE,
            Vec3::new(f32::NAN, 0.0, 0.0),
            Vec3::splat(f32::INFINITY),
            Vec3::new(0.5, f32::NEG_INFINITY, 0.0),
        ],
    });
    world.run_system_once(accumulate_film).unwrap();
    assert_eq!(world.resource::<RenderStats>().nonfinite_samples, 3);
    let film = world.resource::<Film>();
    assert_eq!(film.count, vec![1, 0, 0, 0]);
    assert!(film.image().iter().all(|p| p.is_finite()));
    assert_eq!(film.pixel(0, 0), Vec3::ONE);
}
