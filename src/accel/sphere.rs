//! Ray/sphere intersection following Eric Haines, Johannes Günther and Tomas
//! Akenine-Möller, "Precision Improvements for Ray/Sphere Intersection",
//! Ray Tracing Gems, ch. 7, 2019.
//!
//! Two changes to the textbook quadratic keep it accurate for tiny and huge
//! spheres and for spheres far from the ray origin: the discriminant is
//! computed from the perpendicular distance of the centre to the ray line,
//! `r² − |f − (f·d̂)d̂|²`, instead of `b² − 4ac` (which cancels
//! catastrophically), and the two roots are `c/q` and `q/a` with
//! `q = b' + sign(b')·sqrt(Δ)`, so no root is a difference of near-equal values.

use glam::{Vec2, Vec3};

use super::Ray;

/// Nearest t in (0, t_max) where the ray meets the sphere (the far root when the origin is inside).
pub fn intersect_sphere(ray: &Ray, center: glam::Vec3, radius: f32, t_max: f32) -> Option<f32> {
    let (t0, t1) = sphere_roots(ray, center, radius)?;
    if t0 > 0.0 && t0 < t_max {
        Some(t0)
    } else if t1 > 0.0 && t1 < t_max {
        Some(t1)
    } else {
        None
    }
}

/// Both roots `t0 <= t1` of the ray's line with the sphere, or None when it misses.
pub fn sphere_roots(ray: &Ray, center: glam::Vec3, radius: f32) -> Option<(f32, f32)> {
    let f = ray.origin - center;
    let d = ray.dir;
    let a = d.dot(d);
    // Half of the usual b, negated: the roots are (b ± sqrt(disc)) / a.
    let b = -f.dot(d);
    let c = f.dot(f) - radius * radius;
    // Perpendicular offset from the centre to the ray line; its length is exact
    // enough even when |f| is huge compared to the radius.
    let perp = f + (b / a) * d;
    let disc = a * (radius * radius - perp.dot(perp));
    // NaN comes from a zero direction.
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let q = b + b.signum() * disc.sqrt();
    if q == 0.0 {
        // Only when b = 0 and disc = 0: the origin is the tangent point, t = 0.
        return None;
    }
    let r0 = c / q;
    let r1 = q / a;
    Some(if r0 <= r1 { (r0, r1) } else { (r1, r0) })
}

/// Texture coordinate on a sphere for the unit normal `n`: u around +y, v from the bottom pole.
pub fn sphere_uv(n: Vec3) -> Vec2 {
    let u = 0.5 + (-n.z).atan2(n.x) / std::f32::consts::TAU;
    let v = 1.0 - n.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
    Vec2::new(u, v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec3, vec3};

    fn rel(a: f32, b: f32) -> f32 {
        ((a - b) / b).abs()
    }

    #[test]
    fn unit_sphere_front_and_back() {
        let r = Ray::new(vec3(0.0, 0.0, -5.0), vec3(0.0, 0.0, 1.0));
        assert_eq!(
            intersect_sphere(&r, Vec3::ZERO, 1.0, f32::INFINITY),
            Some(4.0)
        );
        // Limited t_max: the front root is beyond it.
        assert_eq!(intersect_sphere(&r, Vec3::ZERO, 1.0, 3.9), None);
        // Non-unit direction: t is in units of dir.
        let r2 = Ray::new(vec3(0.0, 0.0, -5.0), vec3(0.0, 0.0, 2.0));
        assert_eq!(
            intersect_sphere(&r2, Vec3::ZERO, 1.0, f32::INFINITY),
            Some(2.0)
        );
        // Pointing away.
        let r3 = Ray::new(vec3(0.0, 0.0, -5.0), vec3(0.0, 0.0, -1.0));
        assert_eq!(intersect_sphere(&r3, Vec3::ZERO, 1.0, f32::INFINITY), None);
        // Passing beside.
        let r4 = Ray::new(vec3(0.0, 1.5, -5.0), vec3(0.0, 0.0, 1.0));
        assert_eq!(intersect_sphere(&r4, Vec3::ZERO, 1.0, f32::INFINITY), None);
    }

    #[test]
    fn origin_inside_gives_far_root() {
        let r = Ray::new(vec3(0.0, 0.0, 0.5), vec3(0.0, 0.0, 1.0));
        assert_eq!(
            intersect_sphere(&r, Vec3::ZERO, 1.0, f32::INFINITY),
            Some(0.5)
        );
        let r = Ray::new(vec3(0.0, 0.0, 0.5), vec3(0.0, 0.0, -1.0));
        assert_eq!(
            intersect_sphere(&r, Vec3::ZERO, 1.0, f32::INFINITY),
            Some(1.5)
        );
    }

    #[test]
    fn tangent_rays_no_nan() {
        // Grazing the top of the sphere: the double root t = 5.
        let r = Ray::new(vec3(0.0, 1.0, -5.0), vec3(0.0, 0.0, 1.0));
        let t = intersect_sphere(&r, Vec3::ZERO, 1.0, f32::INFINITY);
        if let Some(t) = t {
            assert!((t - 5.0).abs() < 1e-3, "t {t}");
        }
        // Origin on the sphere, tangent direction: t = 0 only, so no hit.
        let r = Ray::new(vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, 1.0));
        assert_eq!(intersect_sphere(&r, Vec3::ZERO, 1.0, f32::INFINITY), None);
        // Zero direction never yields NaN.
        let r = Ray::new(vec3(0.0, 0.0, -5.0), Vec3::ZERO);
        assert_eq!(intersect_sphere(&r, Vec3::ZERO, 1.0, f32::INFINITY), None);
    }

    #[test]
    fn tiny_sphere() {
        let r = Ray::new(Vec3::ZERO, vec3(1.0, 1.0, 0.0).normalize());
        let c = vec3(1.0, 1.0, 0.0);
        let radius = 1e-6;
        let t = intersect_sphere(&r, c, radius, f32::INFINITY).unwrap();
        let expect = 2.0f32.sqrt() - radius;
        assert!(rel(t, expect) < 1e-4, "t {t} expected {expect}");
        // Offset sideways by 2 radii: a miss.
        let r2 = Ray::new(vec3(0.0, 0.0, 2e-6), r.dir);
        assert_eq!(intersect_sphere(&r2, c, radius, f32::INFINITY), None);
    }

    #[test]
    fn huge_sphere() {
        let radius = 1e6;
        let r = Ray::new(vec3(0.0, 0.0, -3e6), vec3(0.0, 0.0, 1.0));
        let t = intersect_sphere(&r, Vec3::ZERO, radius, f32::INFINITY).unwrap();
        assert!(rel(t, 2e6) < 1e-4, "t {t}");
        // Inside a huge sphere, near its centre, off axis.
        let r = Ray::new(vec3(3.0, -2.0, 1.0), vec3(0.0, 1.0, 0.0));
        let t = intersect_sphere(&r, Vec3::ZERO, radius, f32::INFINITY).unwrap();
        let expect = 2.0 + (radius as f64 * radius as f64 - 10.0).sqrt() as f32;
        assert!(rel(t, expect) < 1e-4, "t {t}");
    }

    #[test]
    fn far_from_origin() {
        // Unit sphere at 1e5, ray slightly off-centre: the textbook b²−4ac
        // loses every digit of the discriminant here.
        let c = vec3(1e5, 0.0, 0.0);
        let r = Ray::new(Vec3::ZERO, vec3(1.0, 0.0, 0.0));
        let off = 0.6f32;
        let r = Ray::new(r.origin + vec3(0.0, off, 0.0), r.dir);
        let t = intersect_sphere(&r, c, 1.0, f32::INFINITY).unwrap();
        let expect = 1e5 - (1.0 - off * off).sqrt();
        assert!(rel(t, expect) < 1e-4, "t {t} expected {expect}");
        // Just past the silhouette: a miss.
        let r = Ray::new(vec3(0.0, 1.001, 0.0), vec3(1.0, 0.0, 0.0));
        assert_eq!(intersect_sphere(&r, c, 1.0, f32::INFINITY), None);
        // Just inside it: a hit.
        let r = Ray::new(vec3(0.0, 0.999, 0.0), vec3(1.0, 0.0, 0.0));
        assert!(intersect_sphere(&r, c, 1.0, f32::INFINITY).is_some());
        // Oblique ray towards a far sphere; check the hit lies on the sphere.
        let c = vec3(1e5, 2e4, -3e4);
        let target = c + vec3(-0.3, 0.4, -0.5).normalize() * 2.0;
        let r = Ray::new(Vec3::ZERO, target.normalize());
        let t = intersect_sphere(&r, c, 2.0, f32::INFINITY).unwrap();
        let p = r.origin.as_dvec3() + r.dir.as_dvec3() * t as f64;
        let dist = (p - c.as_dvec3()).length();
        assert!((dist - 2.0).abs() < 0.05, "hit {dist} from centre");
    }
}
