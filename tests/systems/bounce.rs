//! Bounce: one depth level of the wavefront.

use glam::Vec3;
use glint::accel::Ray;
use glint::scene::{PointLight, Settings};
use glint::schedule::{RenderStats, Stage};
use glint::trace::lights::Lights;
use glint::trace::materials::{MaterialData, Materials};
use glint::trace::plan::RenderPlan;
use glint::trace::wavefront::{
    PassRegion, SampleRadiance, ShadowQueue, ShadowRay, Wavefront, advance_depth, gather_radiance,
    intersect_rays, shade_hits, spawn_pass_through_rays, spawn_reflection_rays, trace_shadow_rays,
};

use crate::world::{assert_close, material, queued, run, spheres, surface};

/// A camera ray from +z straight at the origin, and the top of the unit sphere it hits.
fn hit_on_unit_sphere() -> Wavefront {
    Wavefront {
        rays: vec![queued(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, 0)],
        hits: vec![Some(surface(Vec3::Z, Vec3::Z, 0))].into(),
        ..Wavefront::default()
    }
}

fn materials(list: Vec<MaterialData>) -> Materials {
    Materials {
        list,
        ..Materials::default()
    }
}

fn plan(shadow_rays: bool) -> RenderPlan {
    RenderPlan {
        shadow_rays,
        ..RenderPlan::default()
    }
}

#[test]
fn intersect_rays_finds_each_closest_hit() {
    let wf = Wavefront {
        rays: vec![
            queued(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, 0),
            queued(Vec3::new(0.0, 0.0, 5.0), Vec3::Z, 1),
            queued(Vec3::new(3.0, 0.0, 5.0), -Vec3::Z, 2),
        ],
        ..Wavefront::default()
    };
    // Two spheres on the first ray's line: the nearer one (material 1) is hit.
    let geometry = spheres(&[(Vec3::ZERO, 1.0), (Vec3::new(0.0, 0.0, 2.0), 0.5)]);
    let mut world = world![Settings::default(), geometry, wf, RenderStats::default()];
    run(&mut world, intersect_rays);
    let wf = world.resource::<Wavefront>();
    assert_eq!(wf.hits.len(), 3);
    let hit = wf.hits.get(0).expect("the first ray hits");
    assert_close(hit.p, Vec3::new(0.0, 0.0, 2.5));
    assert_close(hit.n, Vec3::Z);
    assert_eq!(hit.material, 1);
    assert_eq!(
        wf.hits.iter().skip(1).collect::<Vec<_>>(),
        [None, None],
        "rays away from the spheres miss"
    );
    assert_eq!(
        world.resource::<RenderStats>().items(Stage::IntersectRays),
        3
    );
}

/// Phong (the default) with one point light: the SPEC closed form at the sphere's top.
fn shade_world(queue_shadows: bool) -> bevy_ecs::world::World {
    let lights = Lights {
        points: vec![PointLight {
            position: Vec3::new(0.0, 4.0, 4.0),
            color: Vec3::splat(2.0),
        }],
        ..Lights::default()
    };
    let kd = Vec3::new(0.5, 0.25, 1.0);
    world![
        Settings::default(),
        plan(queue_shadows),
        lights,
        materials(vec![material(kd, Vec3::splat(0.5), 2.0, 1.0)]),
        PassRegion::default(),
        hit_on_unit_sphere(),
        RenderStats::default()
    ]
}

/// From the hit (0,0,1) with n = +z: l = (0, 0.8, 0.6), n.l = 0.6; v = +z,
/// r = reflect(-l, n) = (0, -0.8, 0.6), r.v = 0.6. Phong: 2 kd 0.6 + 2 ks 0.6^2.
fn phong_closed_form() -> Vec3 {
    2.0 * Vec3::new(0.5, 0.25, 1.0) * 0.6 + 2.0 * 0.5 * 0.36
}

#[test]
fn shade_hits_queues_the_closed_form_radiance_as_a_shadow_ray() {
    let mut world = shade_world(true);
    run(&mut world, shade_hits);
    let wf = world.resource::<Wavefront>();
    assert_eq!(wf.ray_radiance, [Vec3::ZERO], "it waits for its shadow ray");
    assert_eq!(wf.shadow_rays.len(), 1);
    let s = wf.shadow_rays.to_vec()[0];
    assert_eq!(s.owner, 0);
    assert_close(s.contribution, phong_closed_form());
    assert_close(s.ray.origin, Vec3::Z);
    assert_close(s.ray.origin + s.ray.dir, Vec3::new(0.0, 4.0, 4.0));
    assert_eq!(world.resource::<RenderStats>().items(Stage::ShadeHits), 1);
}

#[test]
fn shade_hits_reuses_its_shadow_buffers_without_keeping_old_rays() {
    let mut world = shade_world(true);
    run(&mut world, shade_hits);
    let first = world.resource::<Wavefront>().shadow_rays.clone();
    run(&mut world, shade_hits);
    assert_eq!(
        world.resource::<Wavefront>().shadow_rays,
        first,
        "the same hit casts the same shadow ray, once"
    );
    // A depth whose only ray misses casts none, whatever the last one left behind.
    world.resource_mut::<Wavefront>().hits = vec![None].into();
    run(&mut world, shade_hits);
    let wf = world.resource::<Wavefront>();
    assert!(wf.shadow_rays.is_empty());
    assert!(
        wf.shadow_rays.chunk_capacity(0) >= 1,
        "the chunk's buffer is kept for the next depth"
    );
}

#[test]
fn shade_hits_overwrites_what_the_last_depth_left_in_its_radiance_buffer() {
    // The buffer is reused across depths and not cleared first: every entry must be
    // written, and entries past the queue dropped.
    for queue_shadows in [true, false] {
        let mut world = shade_world(queue_shadows);
        world.resource_mut::<Wavefront>().ray_radiance = vec![Vec3::splat(7.0); 3];
        run(&mut world, shade_hits);
        let expected = if queue_shadows {
            Vec3::ZERO
        } else {
            phong_closed_form()
        };
        let wf = world.resource::<Wavefront>();
        assert_eq!(wf.ray_radiance.len(), 1, "queue_shadows {queue_shadows}");
        assert_close(wf.ray_radiance[0], expected);
    }
}

#[test]
fn shade_hits_adds_the_closed_form_radiance_without_shadow_rays() {
    let mut world = shade_world(false);
    run(&mut world, shade_hits);
    let wf = world.resource::<Wavefront>();
    assert_eq!(wf.ray_radiance.len(), 1);
    assert_close(wf.ray_radiance[0], phong_closed_form());
    assert!(wf.shadow_rays.is_empty());
}

#[test]
fn shade_hits_gives_misses_the_weighted_background() {
    let mut world = shade_world(true);
    world.resource_mut::<Settings>().background = Vec3::new(0.2, 0.4, 0.6);
    {
        let mut wf = world.resource_mut::<Wavefront>();
        wf.rays[0].weight = Vec3::splat(0.5);
        wf.hits.set(0, None);
    }
    run(&mut world, shade_hits);
    let wf = world.resource::<Wavefront>();
    assert_close(wf.ray_radiance[0], Vec3::new(0.1, 0.2, 0.3));
    assert!(wf.shadow_rays.is_empty());
}

/// Two shadow rays along the x axis: one through the unit sphere, one above it.
fn shadow_world(transparent: bool, alpha: f32) -> bevy_ecs::world::World {
    let shadow = |y: f32, owner: u32| ShadowRay {
        ray: Ray {
            origin: Vec3::new(-5.0, y, 0.0),
            dir: Vec3::new(10.0, 0.0, 0.0),
        },
        contribution: Vec3::new(1.0, 2.0, 3.0),
        owner,
    };
    let wf = Wavefront {
        ray_radiance: vec![Vec3::splat(0.5); 2],
        shadow_rays: ShadowQueue::from_rays(&[shadow(0.0, 0), shadow(3.0, 1)]),
        ..Wavefront::default()
    };
    let plan = RenderPlan {
        transparent_shadows: transparent,
        ..plan(true)
    };
    world![
        plan,
        spheres(&[(Vec3::ZERO, 1.0)]),
        materials(vec![material(Vec3::ONE, Vec3::ZERO, 1.0, alpha)]),
        wf,
        RenderStats::default()
    ]
}

#[test]
fn trace_shadow_rays_adds_only_unoccluded_contributions() {
    let mut world = shadow_world(false, 1.0);
    run(&mut world, trace_shadow_rays);
    let wf = world.resource::<Wavefront>();
    assert_eq!(
        wf.ray_radiance[0],
        Vec3::splat(0.5),
        "blocked by the sphere"
    );
    assert_close(wf.ray_radiance[1], Vec3::new(1.5, 2.5, 3.5));
    let stats = world.resource::<RenderStats>();
    assert_eq!(stats.rays.shadow, 2);
    assert_eq!(stats.items(Stage::TraceShadowRays), 2);
}

#[test]
fn trace_shadow_rays_tints_light_through_transparent_surfaces() {
    // kd = 1, alpha = 0.5: each of the sphere's two surfaces passes (1 - 0.5) * 1.
    let mut world = shadow_world(true, 0.5);
    run(&mut world, trace_shadow_rays);
    let wf = world.resource::<Wavefront>();
    assert_close(
        wf.ray_radiance[0],
        Vec3::splat(0.5) + 0.25 * Vec3::new(1.0, 2.0, 3.0),
    );
    assert_close(wf.ray_radiance[1], Vec3::new(1.5, 2.5, 3.5));
}

#[test]
fn gather_radiance_adds_each_ray_to_its_camera_sample() {
    let wf = Wavefront {
        rays: vec![
            queued(Vec3::ZERO, Vec3::Z, 1),
            queued(Vec3::ZERO, Vec3::Z, 0),
            queued(Vec3::ZERO, Vec3::Z, 1),
        ],
        ray_radiance: vec![Vec3::X, Vec3::Y, Vec3::Z],
        ..Wavefront::default()
    };
    let radiance = SampleRadiance {
        first_pixel: 7,
        values: vec![Vec3::splat(1.0), Vec3::splat(2.0)],
    };
    let mut world = world![wf, radiance];
    run(&mut world, gather_radiance);
    let radiance = world.resource::<SampleRadiance>();
    assert_eq!(radiance.first_pixel, 7);
    assert_eq!(
        radiance.values,
        [Vec3::new(1.0, 2.0, 1.0), Vec3::new(3.0, 2.0, 3.0)]
    );
}

#[test]
fn gather_radiance_of_camera_rays_adds_each_ray_to_its_own_sample() {
    // Rays in sample order over several parallel chunks (`by_sample`): ray i into sample i.
    let n = 3 * 1024 + 5;
    let ray_radiance: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f32, 0.5, -1.0)).collect();
    let wf = Wavefront {
        rays: (0..n as u32)
            .map(|i| queued(Vec3::ZERO, Vec3::Z, i))
            .collect(),
        ray_radiance: ray_radiance.clone(),
        by_sample: true,
        ..Wavefront::default()
    };
    let before: Vec<Vec3> = (0..n).map(|i| Vec3::splat(0.25 * i as f32)).collect();
    let radiance = SampleRadiance {
        first_pixel: 3,
        values: before.clone(),
    };
    let mut world = world![wf, radiance];
    run(&mut world, gather_radiance);
    let values = &world.resource::<SampleRadiance>().values;
    for i in 0..n {
        assert_eq!(values[i], before[i] + ray_radiance[i], "sample {i}");
    }
}

/// One hit on a material with `ks` and `alpha` at `depth`, and one miss.
fn spawn_world(ks: f32, alpha: f32, depth: u32) -> bevy_ecs::world::World {
    let mut wf = hit_on_unit_sphere();
    wf.depth = depth;
    wf.rays[0].slot = 4;
    wf.rays[0].path = 1;
    wf.rays.push(queued(Vec3::new(3.0, 0.0, 5.0), -Vec3::Z, 5));
    wf.hits.push(None);
    let settings = Settings {
        max_depth: 2,
        ..Settings::default()
    };
    world![
        settings,
        materials(vec![material(Vec3::ONE, Vec3::splat(ks), 1.0, alpha)]),
        wf,
        RenderStats::default()
    ]
}

#[test]
fn spawn_reflection_rays_queues_ks_weighted_mirror_rays() {
    let mut world = spawn_world(0.5, 1.0, 1);
    run(&mut world, spawn_reflection_rays);
    let wf = world.resource::<Wavefront>();
    assert_eq!(wf.next.len(), 1, "only the hit reflects");
    let r = wf.next[0];
    assert_eq!(
        (r.slot, r.path),
        (4, 3),
        "same sample, first child of path 1"
    );
    assert_eq!(r.weight, Vec3::splat(0.5));
    assert_close(r.ray.dir, Vec3::Z);
    assert!(
        r.ray.origin.z > 1.0 && r.ray.origin.z < 1.0 + 1e-4,
        "just off the surface"
    );
    assert_eq!(world.resource::<RenderStats>().rays.reflection, 1);
    assert_eq!(wf.rays.len(), 2, "the current rays stay");
}

#[test]
fn spawn_reflection_rays_at_max_depth_queues_none() {
    let mut world = spawn_world(0.5, 1.0, 2);
    run(&mut world, spawn_reflection_rays);
    assert!(world.resource::<Wavefront>().next.is_empty());
    assert_eq!(world.resource::<RenderStats>().rays.reflection, 0);
}

#[test]
fn spawn_reflection_rays_skips_materials_without_ks() {
    let mut world = spawn_world(0.0, 1.0, 0);
    run(&mut world, spawn_reflection_rays);
    assert!(world.resource::<Wavefront>().next.is_empty());
}

#[test]
fn spawn_pass_through_rays_queues_rays_weighted_by_one_minus_alpha() {
    let mut world = spawn_world(0.0, 0.25, 0);
    run(&mut world, spawn_pass_through_rays);
    let wf = world.resource::<Wavefront>();
    assert_eq!(wf.next.len(), 1);
    let r = wf.next[0];
    assert_eq!(
        (r.slot, r.path),
        (4, 4),
        "same sample, second child of path 1"
    );
    assert_eq!(r.weight, Vec3::splat(0.75));
    assert_eq!(r.ray.dir, -Vec3::Z, "straight on");
    assert!(
        r.ray.origin.z < 1.0 && r.ray.origin.z > 1.0 - 1e-4,
        "just past the surface"
    );
    assert_eq!(world.resource::<RenderStats>().rays.pass_through, 1);
}

#[test]
fn spawn_pass_through_rays_skips_opaque_hits_and_max_depth() {
    let mut world = spawn_world(0.0, 1.0, 0);
    run(&mut world, spawn_pass_through_rays);
    assert!(world.resource::<Wavefront>().next.is_empty(), "opaque");
    let mut world = spawn_world(0.0, 0.25, 2);
    run(&mut world, spawn_pass_through_rays);
    assert!(
        world.resource::<Wavefront>().next.is_empty(),
        "at max_depth"
    );
}

#[test]
fn advance_depth_makes_the_next_rays_current() {
    let next = queued(Vec3::ZERO, Vec3::X, 3);
    let wf = Wavefront {
        depth: 2,
        rays: vec![queued(Vec3::ZERO, Vec3::Y, 0); 2],
        next: vec![next],
        by_sample: true,
        ..Wavefront::default()
    };
    let mut world = world![wf];
    run(&mut world, advance_depth);
    let wf = world.resource::<Wavefront>();
    // The next depth's rays are children: no longer one per sample in sample order.
    assert!(!wf.by_sample);
    assert_eq!(wf.depth, 3);
    assert_eq!(wf.rays, [next]);
    assert!(wf.next.is_empty());
}
