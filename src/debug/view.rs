//! The debug view: a camera other than the render's, projection of world points into
//! its image, and clipping at its near plane.

use glam::{Vec2, Vec3};

use crate::accel::Aabb;
use crate::scene::Camera;

/// Near-plane distance as a fraction of the view's distance to what it frames.
const NEAR_FRACTION: f32 = 1e-3;

/// A pinhole camera's basis, for projecting points into its image (the inverse of
/// `trace::wavefront::camera_ray`).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewCamera {
    /// The scene camera it was made from (also used for the background render).
    pub camera: Camera,
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
    /// Near-plane distance along `forward`: points closer are clipped.
    pub near: f32,
}

impl ViewCamera {
    /// The basis of `camera`, with near plane `near`.
    pub fn new(camera: Camera, near: f32) -> Self {
        let forward = (camera.look_at - camera.position).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        Self {
            tan_half: (camera.fov_y_degrees.to_radians() * 0.5).tan(),
            aspect: camera.width as f32 / camera.height as f32,
            camera,
            forward,
            right,
            up,
            near,
        }
    }

    /// Depth of `p` along the view direction.
    pub fn depth(&self, p: Vec3) -> f32 {
        (p - self.camera.position).dot(self.forward)
    }

    /// Image position (pixels, row 0 at the top) and depth of `p`; `None` in front of the near plane.
    pub fn project(&self, p: Vec3) -> Option<(Vec2, f32)> {
        let v = p - self.camera.position;
        let z = v.dot(self.forward);
        if z.is_nan() || z < self.near {
            return None;
        }
        let sx = v.dot(self.right) / (z * self.tan_half * self.aspect);
        let sy = v.dot(self.up) / (z * self.tan_half);
        let (w, h) = (self.camera.width as f32, self.camera.height as f32);
        Some((Vec2::new((sx + 1.0) * 0.5 * w, (1.0 - sy) * 0.5 * h), z))
    }

    /// The part of segment `a`-`b` beyond the near plane, projected; `None` if all of it is behind.
    pub fn project_segment(&self, a: Vec3, b: Vec3) -> Option<((Vec2, f32), (Vec2, f32))> {
        let (za, zb) = (self.depth(a), self.depth(b));
        if za.max(zb).is_nan() || za.max(zb) < self.near {
            return None;
        }
        // Cut at the near plane in world space, so nothing behind the eye is projected.
        let cut = |from: Vec3, z_from: f32, to: Vec3, z_to: f32| {
            let s = (self.near - z_from) / (z_to - z_from);
            from + (to - from) * s
        };
        let a2 = if za < self.near { cut(a, za, b, zb) } else { a };
        let b2 = if zb < self.near { cut(b, zb, a, za) } else { b };
        // Rounding may put a cut point a hair before the plane: project it on the plane.
        let pa = self.project(a2).or_else(|| self.project_on_near(a2))?;
        let pb = self.project(b2).or_else(|| self.project_on_near(b2))?;
        Some((pa, pb))
    }

    fn project_on_near(&self, p: Vec3) -> Option<(Vec2, f32)> {
        let v = p - self.camera.position;
        let z = v.dot(self.forward);
        // NaN fails this test too.
        if z.partial_cmp(&(self.near * 0.5)) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let moved = p + self.forward * (self.near - z);
        self.project(moved)
    }

    /// Pixels per world unit at depth `z`.
    pub fn pixels_per_unit(&self, z: f32) -> f32 {
        self.camera.height as f32 / (2.0 * self.tan_half * z.max(self.near))
    }
}

/// An oblique viewpoint framing `bounds`: the render camera's direction to them turned
/// around its up axis and raised. Of a few such directions, the one that sees the
/// `path` segments (world-space vectors) most from the side wins, so rays do not
/// collapse towards points.
pub fn auto_view(
    render: &Camera,
    bounds: Aabb,
    path: &[Vec3],
    width: u32,
    height: u32,
) -> ViewCamera {
    let center = bounds.centroid();
    let radius = (bounds.extent().length() * 0.5).max(1e-3);
    let up = render.up.normalize_or(Vec3::Y);
    let back = (render.position - center).normalize_or(Vec3::Z);
    let side_on = |dir: Vec3| -> f32 { path.iter().map(|s| s.cross(dir).length()).sum() };
    let mut best: Option<(f32, Vec3)> = None;
    for (yaw, lift) in [
        (35.0f32, 0.45),
        (-35.0, 0.45),
        (55.0, 0.3),
        (-55.0, 0.3),
        (30.0, 1.0),
        (-30.0, 1.0),
    ] {
        let turn = glam::Quat::from_axis_angle(up, yaw.to_radians());
        let mut dir = (turn * back + up * lift).normalize_or(Vec3::Z);
        if dir.cross(up).length() < 1e-3 {
            dir = (dir + up.any_orthonormal_vector() * 0.5).normalize();
        }
        let score = side_on(dir);
        // Keep the first candidate unless another is clearly better.
        if best.is_none_or(|(s, _)| score > s * 1.15) {
            best = Some((score, dir));
        }
    }
    let dir = best.map_or(back, |(_, d)| d);
    view_from(render, center + dir * radius * 3.0, bounds, width, height)
}

/// A viewpoint at `position` looking at the centre of `bounds`, with a field of view
/// that frames them.
pub fn view_from(
    render: &Camera,
    position: Vec3,
    bounds: Aabb,
    width: u32,
    height: u32,
) -> ViewCamera {
    let center = bounds.centroid();
    let radius = (bounds.extent().length() * 0.5).max(1e-3);
    let mut up = render.up.normalize_or(Vec3::Y);
    let forward = (center - position).normalize_or(Vec3::NEG_Z);
    if forward.cross(up).length() < 1e-3 {
        up = forward.any_orthonormal_vector();
    }
    let distance = (center - position).length().max(radius * 1e-3);
    // The half-angle under which the bounding sphere appears, with a margin.
    let half = (radius / distance).clamp(0.0, 1.0).asin().max(0.05) * 1.1;
    let aspect = width as f32 / height as f32;
    let fov_y = if aspect >= 1.0 {
        half * 2.0
    } else {
        2.0 * (half.tan() / aspect).atan()
    };
    let camera = Camera {
        position,
        look_at: center,
        up,
        fov_y_degrees: fov_y.to_degrees().clamp(5.0, 120.0),
        width,
        height,
    };
    ViewCamera::new(camera, (distance * NEAR_FRACTION).max(1e-6))
}
