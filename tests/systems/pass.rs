//! RenderPass: camera samples, the depth loop, the film.

use bevy_ecs::prelude::*;
use glam::{DVec3, Vec3};
use glint::film::estimate::EstimateMethod;
use glint::film::{Film, accumulate_film};
use glint::scene::{Camera, Material, MaterialRef, Settings, Sphere};
use glint::schedule::{RenderStats, Stage, add_render_schedules, run_prepare, trace_wavefronts};
use glint::trace::plan::RenderPlan;
use glint::trace::wavefront::{PassRegion, SampleRadiance, Wavefront, generate_camera_samples};

use crate::world::{assert_close, queued, run};

/// At the origin looking down -z; a 90° field of view puts the image plane's edges at
/// ±1 (times the aspect ratio) one unit away.
fn camera(width: u32, height: u32) -> Camera {
    Camera {
        position: Vec3::ZERO,
        look_at: -Vec3::Z,
        up: Vec3::Y,
        fov_y_degrees: 90.0,
        width,
        height,
    }
}

fn camera_world(region: PassRegion) -> World {
    let mut world = world![
        Settings::default(),
        RenderPlan::default(),
        region,
        Wavefront::default(),
        SampleRadiance::default(),
        RenderStats::default()
    ];
    world.spawn(camera(2, 2));
    world
}

#[test]
fn generate_camera_samples_queues_one_ray_through_each_pixel_centre() {
    let mut world = camera_world(PassRegion {
        sample: 0,
        first_pixel: 0,
        pixels: 4,
    });
    run(&mut world, generate_camera_samples);
    let wf = world.resource::<Wavefront>();
    assert_eq!(wf.depth, 0);
    // Ray i is sample i's (checked below): `gather_radiance` may add them in parallel.
    assert!(wf.by_sample);
    // Row 0 is the top; pixel centres sit half way to the image plane's edges.
    let centres = [(-0.5, 0.5), (0.5, 0.5), (-0.5, -0.5), (0.5, -0.5)];
    assert_eq!(wf.rays.len(), 4);
    for (slot, (q, (x, y))) in wf.rays.iter().zip(centres).enumerate() {
        assert_eq!(q.slot, slot as u32);
        assert_eq!((q.weight, q.path), (Vec3::ONE, 0));
        assert_eq!(q.ray.origin, Vec3::ZERO);
        assert_close(q.ray.dir, Vec3::new(x, y, -1.0).normalize());
    }
    let radiance = world.resource::<SampleRadiance>();
    assert_eq!(
        (radiance.first_pixel, radiance.values.clone()),
        (0, vec![Vec3::ZERO; 4])
    );
    let stats = world.resource::<RenderStats>();
    assert_eq!(stats.rays.camera, 4);
    assert_eq!(stats.items(Stage::GenerateCameraSamples), 4);
}

#[test]
fn generate_camera_samples_covers_only_its_region() {
    let mut world = camera_world(PassRegion {
        sample: 3,
        first_pixel: 2,
        pixels: 2,
    });
    world.resource_mut::<Wavefront>().depth = 5;
    run(&mut world, generate_camera_samples);
    let wf = world.resource::<Wavefront>();
    assert_eq!(wf.depth, 0, "a new wavefront starts at depth 0");
    let slots: Vec<u32> = wf.rays.iter().map(|q| q.slot).collect();
    assert_eq!(slots, [0, 1], "slots count from the region's first pixel");
    assert_close(wf.rays[0].ray.dir, Vec3::new(-0.5, -0.5, -1.0).normalize());
    assert_close(wf.rays[1].ray.dir, Vec3::new(0.5, -0.5, -1.0).normalize());
    let radiance = world.resource::<SampleRadiance>();
    assert_eq!((radiance.first_pixel, radiance.values.len()), (2, 2));
}

#[test]
fn trace_wavefronts_runs_bounces_until_no_ray_remains() {
    // A mirror sphere (ks 0.5, no lights) under a white sky: the camera ray reflects
    // once, the reflection misses, so the sample is half the background after 2 depths.
    let mut world = World::new();
    add_render_schedules(&mut world);
    world.insert_resource(Settings {
        background: Vec3::ONE,
        ..Settings::default()
    });
    let mirror = world
        .spawn(Material {
            ks: Vec3::splat(0.5),
            ..Material::default()
        })
        .id();
    world.spawn((
        Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        },
        MaterialRef(mirror),
    ));
    run_prepare(&mut world).unwrap();
    world.resource_mut::<Wavefront>().rays = vec![queued(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, 0)];
    world.resource_mut::<SampleRadiance>().values = vec![Vec3::ZERO];
    world.insert_resource(RenderStats::default());

    run(&mut world, trace_wavefronts);
    let wf = world.resource::<Wavefront>();
    assert!(wf.rays.is_empty() && wf.next.is_empty());
    assert_eq!(wf.depth, 2);
    assert_close(
        world.resource::<SampleRadiance>().values[0],
        Vec3::splat(0.5),
    );
    let stats = world.resource::<RenderStats>();
    assert_eq!(
        stats.stages[&Stage::IntersectRays].runs,
        2,
        "one bounce per depth"
    );
    assert_eq!(stats.rays.reflection, 1);
}

#[test]
fn accumulate_film_adds_the_radiance_buffer_to_its_pixels() {
    let mut film = Film::new(3, 1);
    film.sum[1] = DVec3::splat(1.0);
    film.count[1] = 1;
    let radiance = SampleRadiance {
        first_pixel: 1,
        values: vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.5, 0.5, 0.5)],
    };
    let region = PassRegion {
        sample: 1,
        first_pixel: 1,
        pixels: 2,
    };
    let mut world = world![film, radiance, region, RenderStats::default()];
    run(&mut world, accumulate_film);
    let film = world.resource::<Film>();
    assert_eq!(film.count, [0, 2, 1]);
    assert_eq!(film.sum[0], DVec3::ZERO, "outside the region");
    assert_eq!(film.sum[1], DVec3::new(2.0, 3.0, 4.0));
    assert_eq!(film.pixel(2, 0), Vec3::splat(0.5));
    assert_eq!(
        world.resource::<RenderStats>().items(Stage::AccumulateFilm),
        2
    );
}

#[test]
fn accumulate_film_counts_and_drops_non_finite_samples() {
    let radiance = SampleRadiance {
        first_pixel: 0,
        values: vec![Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ONE],
    };
    let region = PassRegion {
        sample: 0,
        first_pixel: 0,
        pixels: 2,
    };
    let mut world = world![Film::new(2, 1), radiance, region, RenderStats::default()];
    run(&mut world, accumulate_film);
    let film = world.resource::<Film>();
    assert_eq!(film.count, [0, 1]);
    assert_eq!(film.sum[0], DVec3::ZERO);
    assert_eq!(world.resource::<RenderStats>().nonfinite_samples, 1);
}

#[test]
fn accumulate_film_adds_deviations_and_the_odd_replica() {
    // Pixel 0 already holds one sample of 1.0 (pass 0); pass 1 adds 3.0.
    let mut film = Film::new(2, 1);
    film.sum[0] = DVec3::ONE;
    film.count[0] = 1;
    let radiance = SampleRadiance {
        first_pixel: 0,
        values: vec![Vec3::splat(3.0), Vec3::new(f32::NAN, 0.0, 0.0)],
    };
    let region = PassRegion {
        sample: 1,
        first_pixel: 0,
        pixels: 2,
    };
    let mut world = world![film, radiance, region, RenderStats::default()];
    run(&mut world, accumulate_film);
    let film = world.resource::<Film>();
    // Welford: (3 - 1) * (3 - 2) = 2, the sum of squared deviations of {1, 3}.
    assert_eq!(film.m2[0], DVec3::splat(2.0));
    assert_eq!(
        (film.replica_sum[0], film.replica_count[0]),
        (DVec3::splat(3.0), 1)
    );
    assert_eq!(
        (film.m2[1], film.replica_count[1]),
        (DVec3::ZERO, 0),
        "non-finite"
    );
    // s^2 / n = 2 / 2 = 1; replicas (1 - 3)^2 (1 + 1) / (2 * 4) = 1.
    for method in [EstimateMethod::Moments, EstimateMethod::Replicas] {
        assert_eq!(film.pixel_variance(0, method), Some(DVec3::ONE));
    }
}
