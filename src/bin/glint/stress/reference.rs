//! A tiny f64 reference tracer that says, per pixel, whether a point light should light
//! what the pixel sees: the yardstick for acne (dark where it should be lit) and leaks
//! (lit where it should be dark).
//!
//! It knows rectangles, spheres and axis-aligned boxes, traces one ray through each
//! pixel centre in f64, and decides lit / shadowed / miss. Near a boundary (silhouette,
//! shadow edge, terminator, contact) the f32 render may legitimately decide either way,
//! so each pixel is also decided for rays perturbed by `margin` (world units), with the
//! shadow ray lifted off the surface by `margin`, and by a
//! fiftieth of a pixel; a pixel whose decisions disagree is `Unknown` and not counted.

use glam::{DVec3, Vec3};

use super::Rendered;
use glint::scene::Camera;

/// A reference primitive (two-sided).
#[derive(Clone, Copy, Debug)]
pub enum Prim {
    /// `origin + a*u + b*v`, a and b in [0, 1].
    Rect {
        /// Corner.
        origin: DVec3,
        /// First edge.
        u: DVec3,
        /// Second edge.
        v: DVec3,
    },
    /// A sphere.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// An axis-aligned box.
    Cuboid {
        /// Smallest corner.
        min: DVec3,
        /// Largest corner.
        max: DVec3,
    },
}

/// What a pixel should show under a single point light with shading off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expect {
    /// The ray escapes.
    Miss,
    /// The hit sees the light.
    Lit,
    /// The hit faces away from the light or is shadowed.
    Dark,
    /// Too close to a boundary to tell at f32 precision.
    Unknown,
}

/// Reference scene: primitives, one point light, and the ambiguity margin.
#[derive(Clone, Debug)]
pub struct RefScene {
    /// The primitives.
    pub prims: Vec<Prim>,
    /// The point light.
    pub light: DVec3,
    /// Perturbation (world units) below which a decision is ambiguous.
    pub margin: f64,
}

/// Hit parameter and unit normal of `prim`, for t > `t_min`.
fn hit_prim(prim: &Prim, o: DVec3, d: DVec3, t_min: f64) -> Option<(f64, DVec3)> {
    match *prim {
        Prim::Rect { origin, u, v } => {
            let n = u.cross(v).normalize();
            let denom = d.dot(n);
            if denom == 0.0 {
                return None;
            }
            let t = (origin - o).dot(n) / denom;
            if t <= t_min {
                return None;
            }
            let p = o + t * d - origin;
            // Solve p = a u + b v by the Gram matrix.
            let (uu, uv, vv) = (u.dot(u), u.dot(v), v.dot(v));
            let (pu, pv) = (p.dot(u), p.dot(v));
            let det = uu * vv - uv * uv;
            let a = (pu * vv - pv * uv) / det;
            let b = (pv * uu - pu * uv) / det;
            ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some((t, n))
        }
        Prim::Sphere { center, radius } => {
            let f = o - center;
            let a = d.dot(d);
            let b = -f.dot(d);
            let perp = f + (b / a) * d;
            let disc = a * (radius * radius - perp.dot(perp));
            if disc < 0.0 {
                return None;
            }
            let s = disc.sqrt();
            let (t0, t1) = ((b - s) / a, (b + s) / a);
            let t = if t0 > t_min {
                t0
            } else if t1 > t_min {
                t1
            } else {
                return None;
            };
            Some((t, (o + t * d - center).normalize()))
        }
        Prim::Cuboid { min, max } => {
            let mut t_near = f64::NEG_INFINITY;
            let mut t_far = f64::INFINITY;
            let mut n_near = DVec3::ZERO;
            let mut n_far = DVec3::ZERO;
            for k in 0..3 {
                if d[k] == 0.0 {
                    if o[k] < min[k] || o[k] > max[k] {
                        return None;
                    }
                    continue;
                }
                let (t0, t1) = ((min[k] - o[k]) / d[k], (max[k] - o[k]) / d[k]);
                let (ta, tb) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
                let mut axis = DVec3::ZERO;
                axis[k] = 1.0;
                if ta > t_near {
                    t_near = ta;
                    n_near = axis;
                }
                if tb < t_far {
                    t_far = tb;
                    n_far = axis;
                }
            }
            if t_near > t_far {
                None
            } else if t_near > t_min {
                Some((t_near, n_near))
            } else if t_far > t_min {
                Some((t_far, n_far))
            } else {
                None
            }
        }
    }
}

impl RefScene {
    /// Closest hit: (t, primitive, normal).
    fn closest(&self, o: DVec3, d: DVec3) -> Option<(f64, usize, DVec3)> {
        let mut best: Option<(f64, usize, DVec3)> = None;
        for (i, p) in self.prims.iter().enumerate() {
            if let Some((t, n)) = hit_prim(p, o, d, 0.0)
                && best.is_none_or(|b| t < b.0)
            {
                best = Some((t, i, n));
            }
        }
        best
    }

    /// Whether the light is visible from `p` on primitive `own` with normal `n` facing `-d`.
    fn sees_light(&self, p: DVec3, n: DVec3, own: usize) -> bool {
        let l = self.light - p;
        if n.dot(l) <= 0.0 {
            return false;
        }
        !self
            .prims
            .iter()
            .enumerate()
            .any(|(i, prim)| i != own && hit_prim(prim, p, l, 1e-12).is_some_and(|(t, _)| t < 1.0))
    }

    /// The decision for one ray, the shadow ray starting `lift` off the surface (as the
    /// tracer's offset origins do).
    fn decide(&self, o: DVec3, d: DVec3, lift: f64) -> Expect {
        match self.closest(o, d) {
            None => Expect::Miss,
            Some((t, i, n)) => {
                let n = if n.dot(d) > 0.0 { -n } else { n };
                if self.sees_light(o + t * d + lift * n, n, i) {
                    Expect::Lit
                } else {
                    Expect::Dark
                }
            }
        }
    }

    /// What pixel `(x, y)` of `camera` should show (ray through the pixel centre).
    pub fn expect(&self, camera: &Camera, x: u32, y: u32) -> Expect {
        let m = self.margin;
        let centre = self.decide_pixel(camera, x as f64 + 0.5, y as f64 + 0.5, DVec3::ZERO);
        let pixel = 0.02;
        let jitters = [(pixel, 0.0), (-pixel, 0.0), (0.0, pixel), (0.0, -pixel)];
        for (dx, dy) in jitters {
            let e = self.decide_pixel(
                camera,
                x as f64 + 0.5 + dx,
                y as f64 + 0.5 + dy,
                DVec3::ZERO,
            );
            if e != centre {
                return Expect::Unknown;
            }
        }
        // Shifted eyes move the hit along the surface, lifts move the shadow origin off it
        // (lifted origins can enter a nearby object at one height and not another).
        let (o, d) = camera_ray_f64(camera, x as f64 + 0.5, y as f64 + 0.5);
        let shifts = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ];
        for shift in shifts {
            for lift in [0.0, 0.125, 0.25, 0.5, 0.75, 1.0] {
                if self.decide(o + shift * m, d, lift * m) != centre {
                    return Expect::Unknown;
                }
            }
        }
        centre
    }

    fn decide_pixel(&self, camera: &Camera, x: f64, y: f64, delta: DVec3) -> Expect {
        let (o, d) = camera_ray_f64(camera, x, y);
        // Also move the eye, so silhouettes are fuzzy by the margin too.
        self.decide(o + delta, d, 0.0)
    }

    /// Counts acne (should be lit, rendered dark), leaks (should be dark, rendered lit),
    /// wrong misses and hits, and the pixels decided, for a shading-off render whose lit
    /// value is `lit`.
    pub fn count(&self, camera: &Camera, img: &Rendered, lit: Vec3) -> Counts {
        let mut c = Counts::default();
        let half = lit.max_element() * 0.5;
        for y in 0..img.height {
            for x in 0..img.width {
                let v = img.image[(y * img.width + x) as usize].max_element();
                match self.expect(camera, x, y) {
                    Expect::Unknown => c.unknown += 1,
                    Expect::Lit => {
                        c.lit += 1;
                        if v.is_nan() || v <= half {
                            c.acne += 1;
                        }
                    }
                    Expect::Dark => {
                        c.dark += 1;
                        if v.is_nan() || v >= half {
                            c.leaks += 1;
                        }
                    }
                    Expect::Miss => {
                        if v != 0.0 {
                            c.wrong_miss += 1;
                        }
                    }
                }
            }
        }
        c
    }
}

/// Per-image acne and leak counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Pixels that should be lit.
    pub lit: u64,
    /// Pixels that should be dark (shadowed or facing away).
    pub dark: u64,
    /// Pixels too close to a boundary to decide.
    pub unknown: u64,
    /// Lit pixels rendered dark.
    pub acne: u64,
    /// Dark pixels rendered lit.
    pub leaks: u64,
    /// Pixels that should miss everything but show something.
    pub wrong_miss: u64,
}

/// The camera ray through image position `(x, y)` in f64 (same formula as the tracer's).
pub fn camera_ray_f64(camera: &Camera, x: f64, y: f64) -> (DVec3, DVec3) {
    let position = camera.position.as_dvec3();
    let forward = (camera.look_at.as_dvec3() - position).normalize();
    let right = forward.cross(camera.up.as_dvec3()).normalize();
    let up = right.cross(forward);
    let tan = ((camera.fov_y_degrees as f64).to_radians() * 0.5).tan();
    let aspect = camera.width as f64 / camera.height as f64;
    let sx = (2.0 * x / camera.width as f64 - 1.0) * tan * aspect;
    let sy = (1.0 - 2.0 * y / camera.height as f64) * tan;
    (position, (forward + sx * right + sy * up).normalize())
}
