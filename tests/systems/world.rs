//! Builders of the tiny Worlds and the values the system tests put in them.

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use glam::{Vec2, Vec3};
use glint::accel::{Aabb, Bvh, Ray, SplitMethod};
use glint::scene::{Material, Sphere};
use glint::trace::geometry::SceneGeometry;
use glint::trace::materials::MaterialData;
use glint::trace::surface::Surface;
use glint::trace::wavefront::QueuedRay;

/// Runs `system` once on `world`.
pub fn run<M>(world: &mut World, system: impl IntoSystem<(), (), M>) {
    world.run_system_once(system).expect("the system runs");
}

/// A camera ray (weight 1, root of its tree) for camera sample `slot`.
pub fn queued(origin: Vec3, dir: Vec3, slot: u32) -> QueuedRay {
    QueuedRay {
        ray: Ray { origin, dir },
        weight: Vec3::ONE,
        slot,
        path: 0,
    }
}

/// A shading point at `p` facing `n`, made of material `material`.
pub fn surface(p: Vec3, n: Vec3, material: u32) -> Surface {
    Surface {
        p,
        p_error: Vec3::ZERO,
        ng: n,
        n,
        uv: Vec2::ZERO,
        material,
    }
}

/// An untextured material as the tracer reads it.
pub fn material(kd: Vec3, ks: Vec3, shininess: f32, alpha: f32) -> MaterialData {
    MaterialData {
        kd,
        ks,
        shininess,
        alpha,
        texture: None,
        wrap: Material::default().wrap,
    }
}

/// Geometry of spheres `(centre, radius)`, sphere `i` made of material `i`, under a BVH.
pub fn spheres(list: &[(Vec3, f32)]) -> SceneGeometry {
    let spheres: Vec<Sphere> = list
        .iter()
        .map(|&(center, radius)| Sphere { center, radius })
        .collect();
    let bounds: Vec<Aabb> = spheres
        .iter()
        .map(|s| Aabb {
            min: s.center - Vec3::splat(s.radius),
            max: s.center + Vec3::splat(s.radius),
        })
        .collect();
    SceneGeometry {
        sphere_material: (0..spheres.len() as u32).collect(),
        sphere_bvh: Bvh::build(&bounds, SplitMethod::SahBinned),
        spheres,
        ..Default::default()
    }
}

/// Asserts two vectors agree within 1e-5 per component.
#[track_caller]
pub fn assert_close(actual: Vec3, expected: Vec3) {
    assert!(
        (actual - expected).abs().max_element() <= 1e-5,
        "got {actual}, expected {expected}"
    );
}
