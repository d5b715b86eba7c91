//! The pinhole camera model: the ray through an image position, and its inverse, the
//! image position of a world point. The render, the debug view and its overlay all use it.

use glam::Vec3;
use multiversion::multiversion;

use crate::accel::Ray;
use crate::scene::Camera;

/// A camera's frame, computed once per pass rather than once per ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraBasis {
    /// Eye position.
    pub origin: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Unit right vector.
    pub right: Vec3,
    /// Unit up vector, orthogonal to `forward` and `right`.
    pub up: Vec3,
    /// `tan(fov_y / 2)`.
    pub tan_half: f32,
    /// Width over height.
    pub aspect: f32,
    /// Image width in pixels.
    pub width: f32,
    /// Image height in pixels.
    pub height: f32,
}

impl CameraBasis {
    /// The frame of `camera`.
    pub fn new(camera: &Camera) -> Self {
        let forward = (camera.look_at - camera.position).normalize();
        let right = forward.cross(camera.up).normalize();
        Self {
            origin: camera.position,
            forward,
            right,
            up: right.cross(forward),
            tan_half: (camera.fov_y_degrees.to_radians() * 0.5).tan(),
            aspect: camera.width as f32 / camera.height as f32,
            width: camera.width as f32,
            height: camera.height as f32,
        }
    }

    /// The ray through image-plane position `(x, y)` in pixels (row 0 at the top).
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width - 1.0) * self.tan_half * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height) * self.tan_half;
        Ray {
            origin: self.origin,
            dir: (self.forward + sx * self.right + sy * self.up).normalize(),
        }
    }

    /// [`Self::ray`]'s direction at `(x[j], y[j])` in each lane `j`, bit for bit (the
    /// same operations in the same order; the origin is `self.origin`).
    pub fn dirs_lanes(&self, x: &[f32; LANES], y: &[f32; LANES], dir: &mut [[f32; LANES]; 3]) {
        dirs_lanes(self, x, y, dir);
    }

    /// Depth of `p` along the view direction.
    pub fn depth(&self, p: Vec3) -> f32 {
        (p - self.origin).dot(self.forward)
    }

    /// The inverse of [`CameraBasis::ray`]: image position `(x, y)` in pixels and depth of
    /// `p`; `None` unless `p` is in front of the eye.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32, f32)> {
        let v = p - self.origin;
        let z = v.dot(self.forward);
        if z.is_nan() || z <= 0.0 {
            return None;
        }
        let sx = v.dot(self.right) / (z * self.tan_half * self.aspect);
        let sy = v.dot(self.up) / (z * self.tan_half);
        Some((
            (sx + 1.0) * 0.5 * self.width,
            (1.0 - sy) * 0.5 * self.height,
            z,
        ))
    }

    /// Height of the image plane in world units at depth `z`.
    pub fn height_at(&self, z: f32) -> f32 {
        2.0 * self.tan_half * z
    }
}

/// The camera's ray through image-plane position `(x, y)` in pixels (row 0 at the top).
pub fn camera_ray(camera: &Camera, x: f32, y: f32) -> Ray {
    CameraBasis::new(camera).ray(x, y)
}

/// Lanes of [`CameraBasis::dirs_lanes`].
const LANES: usize = crate::sampling::SLOT_LANES;

/// [`CameraBasis::dirs_lanes`], in an AVX2 clone.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn dirs_lanes(b: &CameraBasis, x: &[f32; LANES], y: &[f32; LANES], dir: &mut [[f32; LANES]; 3]) {
    let (f, r, u) = (b.forward.to_array(), b.right.to_array(), b.up.to_array());
    for j in 0..LANES {
        let sx = (2.0 * x[j] / b.width - 1.0) * b.tan_half * b.aspect;
        let sy = (1.0 - 2.0 * y[j] / b.height) * b.tan_half;
        let d: [f32; 3] = std::array::from_fn(|a| f[a] + sx * r[a] + sy * u[a]);
        // glam's `normalize`: times `1 / length`, the dot product left to right.
        let rcp = 1.0 / ((d[0] * d[0]) + (d[1] * d[1]) + (d[2] * d[2])).sqrt();
        for a in 0..3 {
            dir[a][j] = d[a] * rcp;
        }
    }
}
