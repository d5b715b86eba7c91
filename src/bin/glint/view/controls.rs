//! Camera controls: orbit, pan and zoom about the point looked at, and WASD/QE flight.
//! Pure functions of a [`Camera`], so the tests check them without a window.

use glam::{Mat4, Quat, Vec3};
use glint::scene::Camera;

/// Radians of orbit per point of mouse drag.
pub const ORBIT_PER_POINT: f32 = 0.01;
/// Closest the orbit may come to the up axis, in radians, so the view never flips.
const POLE_MARGIN: f32 = 0.02;

/// The world-to-camera matrix of `c` (right-handed, looking down -z).
#[allow(
    dead_code,
    reason = "for tests/view.rs, which checks what a drag does to it"
)]
pub fn view_matrix(c: &Camera) -> Mat4 {
    glam::camera::rh::view::look_at_mat4(c.position, c.look_at, c.up)
}

/// Turns the eye about the point looked at: `dx` about the up axis, `dy` toward or
/// away from it, in points of drag. Dragging right turns the scene to the right (the
/// eye moves left).
pub fn orbit(c: &mut Camera, dx: f32, dy: f32) {
    let up = c.up.normalize();
    let offset = c.position - c.look_at;
    let yaw = Quat::from_axis_angle(up, -dx * ORBIT_PER_POINT);
    let mut offset = yaw * offset;
    // The angle from the up axis; rotating about `right` by `pitch` adds `pitch` to it.
    let polar = offset.normalize().dot(up).clamp(-1.0, 1.0).acos();
    let pitch = (-dy * ORBIT_PER_POINT).clamp(
        POLE_MARGIN - polar,
        std::f32::consts::PI - POLE_MARGIN - polar,
    );
    let right = up.cross(offset).normalize_or_zero();
    if right != Vec3::ZERO {
        offset = Quat::from_axis_angle(right, pitch) * offset;
    }
    c.position = c.look_at + offset;
}

/// Slides the eye and the point looked at across the view by `dx`, `dy` points, so the
/// scene follows the mouse; `height` is the view's height in points.
pub fn pan(c: &mut Camera, dx: f32, dy: f32, height: f32) {
    let forward = c.look_at - c.position;
    let right = forward.cross(c.up).normalize_or_zero();
    let up = right.cross(forward).normalize_or_zero();
    // World units per point at the distance of the point looked at.
    let scale =
        2.0 * (0.5 * c.fov_y_degrees.to_radians()).tan() * forward.length() / height.max(1.0);
    let shift = (-dx * right + dy * up) * scale;
    c.position += shift;
    c.look_at += shift;
}

/// Moves the eye toward the point looked at (`steps > 0`) or away, 10% of the
/// distance per step, never through it.
pub fn zoom(c: &mut Camera, steps: f32) {
    let offset = c.position - c.look_at;
    c.position = c.look_at + offset * 0.9f32.powf(steps).max(1e-3);
}

/// Flies the eye and the point looked at along the view: `forward`, `right`, `up` in
/// units of the distance between them.
pub fn fly(c: &mut Camera, forward: f32, right: f32, up: f32) {
    let f = c.look_at - c.position;
    let r = f.cross(c.up).normalize_or_zero();
    let u = c.up.normalize_or_zero();
    let d = f.length();
    let shift = (f.normalize_or_zero() * forward + r * right + u * up) * d;
    c.position += shift;
    c.look_at += shift;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            position: Vec3::new(0.0, 0.0, 5.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_degrees: 40.0,
            width: 100,
            height: 100,
        }
    }

    #[test]
    fn orbit_keeps_the_distance_and_stops_short_of_the_pole() {
        let mut c = camera();
        orbit(&mut c, 0.0, 1000.0);
        assert!((c.position.length() - 5.0).abs() < 1e-4);
        assert!(c.position.normalize().dot(Vec3::Y) < 1.0 - 1e-5);
        assert!(view_matrix(&c).is_finite());
    }

    #[test]
    fn zoom_and_fly_move_along_the_view() {
        let mut c = camera();
        zoom(&mut c, 1.0);
        assert!((c.position.z - 4.5).abs() < 1e-5);
        fly(&mut c, 0.5, 0.0, 0.0);
        assert!((c.position.z - 2.25).abs() < 1e-5 && (c.look_at.z + 2.25).abs() < 1e-5);
    }

    #[test]
    fn pan_moves_the_eye_and_the_target_together() {
        let mut c = camera();
        pan(&mut c, 10.0, 0.0, 100.0);
        assert!(c.position.x < 0.0 && (c.position.x - c.look_at.x).abs() < 1e-6);
    }
}
