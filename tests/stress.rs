//! Every `glint stress` case as a test, at the quick budget (small images, 40k rays per
//! mesh). Each fails if any of its measurements is outside its bound.

use glint::stress::{Budget, Row, cases, csv, run_case, table};

fn check(name: &str) {
    let case = cases()
        .into_iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no stress case {name}"));
    let rows = run_case(&case, &Budget::quick());
    let failed: Vec<&Row> = rows.iter().filter(|r| !r.pass).collect();
    assert!(
        failed.is_empty(),
        "stress case {name} failed:\n{}",
        table(&rows)
    );
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

#[test]
fn every_case_has_a_test() {
    let source = include_str!("stress.rs");
    for c in cases() {
        assert!(
            source.contains(&format!("check(\"{}\")", c.name)),
            "no test for case {}",
            c.name
        );
    }
}

#[test]
fn rows_fail_outside_their_bound_and_on_nan() {
    assert!(Row::at_most("c", "m", 0.0, 0.0).pass);
    assert!(!Row::at_most("c", "m", 1.0, 0.0).pass);
    assert!(!Row::at_most("c", "m", f64::NAN, 0.0).pass);
    assert!(!Row::exactly("c", "m", 2.0, 3.0).pass);
    let rows = [Row::at_most("a \"b\"", "m", 1.5, 2.0)];
    assert_eq!(
        csv(&rows),
        "case,measure,value,bound,pass\n\"a \"\"b\"\"\",\"m\",1.5e0,2e0,true\n"
    );
    assert!(table(&rows).contains("| a \"b\" | m | 1.500e0 | 2 | pass |"));
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
    use glint::trace::wavefront::SampleRadiance;

    let mut world = World::new();
    world.insert_resource(Film::new(4, 1));
    world.insert_resource(RenderStats::default());
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
