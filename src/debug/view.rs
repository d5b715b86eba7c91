//! The debug view: a camera other than the render's, projection of world points into
//! its image (the tracer's camera model), and clipping at its near plane.

use glam::{Vec2, Vec3};

use crate::accel::Aabb;
use crate::scene::Camera;
use crate::trace::camera::CameraBasis;

/// Near-plane distance as a fraction of the view's distance to what it frames.
const NEAR_FRACTION: f32 = 1e-3;

/// The debug view: a camera other than the render's, with a near plane. Projection is
/// the tracer's camera model ([`CameraBasis::project`]), the inverse of its rays.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewCamera {
    /// The scene camera it was made from (also used for the background render).
    pub camera: Camera,
    /// Its frame.
    pub basis: CameraBasis,
    /// Near-plane distance along the view direction: points closer are clipped.
    pub near: f32,
}

impl ViewCamera {
    /// The view through `camera`, with near plane `near`.
    pub fn new(camera: Camera, near: f32) -> Self {
        Self {
            basis: CameraBasis::new(&camera),
            camera,
            near,
        }
    }

    /// Depth of `p` along the view direction.
    pub fn depth(&self, p: Vec3) -> f32 {
        self.basis.depth(p)
    }

    /// Image position (pixels, row 0 at the top) and depth of `p`; `None` in front of the near plane.
    pub fn project(&self, p: Vec3) -> Option<(Vec2, f32)> {
        let (x, y, z) = self.basis.project(p)?;
        (z >= self.near).then_some((Vec2::new(x, y), z))
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
        let z = self.depth(p);
        // NaN fails this test too.
        if z.partial_cmp(&(self.near * 0.5)) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let moved = p + self.basis.forward * (self.near - z);
        self.project(moved)
    }

    /// Pixels per world unit at depth `z`.
    pub fn pixels_per_unit(&self, z: f32) -> f32 {
        self.basis.height / self.basis.height_at(z.max(self.near))
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
