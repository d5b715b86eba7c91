//! Samples on area lights (SPEC "Lights and shadows").

use glam::{Vec2, Vec3};

use crate::scene::{ParallelogramLight, SegmentLight};

/// `x` clamped to [0, 1], with NaN sent to 0 so a bad sample cannot poison a light.
fn unit(x: f32) -> f32 {
    // `x < 1.0` rather than `x.min(1.0)`: x is no NaN here, so the two agree, and the
    // comparison is one `minss` where `min` added a NaN-aware blend per sample.
    if x > 0.0 {
        if x < 1.0 { x } else { 1.0 }
    } else {
        0.0
    }
}

/// Position and colour of the segment light at s in [0,1) (SPEC).
///
/// Written as `(1 - s) a + s b` so that both endpoints are reproduced exactly.
pub fn sample_segment_light(light: &SegmentLight, s: f32) -> (Vec3, Vec3) {
    let s = unit(s);
    let position = light.endpoint0 * (1.0 - s) + light.endpoint1 * s;
    let color = light.color0 * (1.0 - s) + light.color1 * s;
    (position, color)
}

/// Position and colour of the parallelogram light at (u, v) in [0,1)^2 (SPEC: bilinear colour).
pub fn sample_parallelogram_light(light: &ParallelogramLight, uv: Vec2) -> (Vec3, Vec3) {
    let (u, v) = (unit(uv.x), unit(uv.y));
    let position = light.v0 + u * light.edge01 + v * light.edge02;
    let color = (1.0 - u) * (1.0 - v) * light.color0
        + u * (1.0 - v) * light.color1
        + (1.0 - u) * v * light.color2
        + u * v * light.color3;
    (position, color)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Sampler, light_dim};

    fn segment() -> SegmentLight {
        SegmentLight {
            endpoint0: Vec3::new(-1.0, 2.0, 3.0),
            endpoint1: Vec3::new(3.0, 2.0, -1.0),
            color0: Vec3::new(1.0, 0.0, 0.0),
            color1: Vec3::new(0.0, 2.0, 4.0),
        }
    }

    fn parallelogram() -> ParallelogramLight {
        ParallelogramLight {
            v0: Vec3::new(1.0, 5.0, -2.0),
            edge01: Vec3::new(2.0, 0.0, 0.0),
            edge02: Vec3::new(1.0, 0.0, 3.0),
            color0: Vec3::new(1.0, 0.0, 0.0),
            color1: Vec3::new(0.0, 1.0, 0.0),
            color2: Vec3::new(0.0, 0.0, 1.0),
            color3: Vec3::new(2.0, 2.0, 2.0),
        }
    }

    #[test]
    fn segment_endpoints_and_middle() {
        let l = segment();
        assert_eq!(sample_segment_light(&l, 0.0), (l.endpoint0, l.color0));
        assert_eq!(sample_segment_light(&l, 1.0), (l.endpoint1, l.color1));
        let (p, c) = sample_segment_light(&l, 0.5);
        assert!(p.abs_diff_eq(Vec3::new(1.0, 2.0, 1.0), 1e-6), "{p}");
        assert!(c.abs_diff_eq(Vec3::new(0.5, 1.0, 2.0), 1e-6), "{c}");
    }

    #[test]
    fn segment_samples_on_segment() {
        let l = segment();
        let s = Sampler::new(1);
        let dir = (l.endpoint1 - l.endpoint0).normalize();
        let len = l.endpoint0.distance(l.endpoint1);
        for i in 0..1000 {
            let (p, _) = sample_segment_light(&l, s.get1(0, i, light_dim(0, 0, 0, 0)));
            let d = p - l.endpoint0;
            let along = d.dot(dir);
            assert!((d - along * dir).length() < 1e-5);
            assert!((-1e-5..=len + 1e-5).contains(&along));
        }
    }

    #[test]
    fn nan_sample_is_finite() {
        let (p, c) = sample_segment_light(&segment(), f32::NAN);
        assert!(p.is_finite() && c.is_finite());
        let (p, c) = sample_parallelogram_light(&parallelogram(), Vec2::NAN);
        assert!(p.is_finite() && c.is_finite());
    }

    #[test]
    fn parallelogram_corners_and_centre() {
        let l = parallelogram();
        let at = |u: f32, v: f32| sample_parallelogram_light(&l, Vec2::new(u, v));
        assert_eq!(at(0.0, 0.0), (l.v0, l.color0));
        assert_eq!(at(1.0, 0.0), (l.v0 + l.edge01, l.color1));
        assert_eq!(at(0.0, 1.0), (l.v0 + l.edge02, l.color2));
        assert_eq!(at(1.0, 1.0).1, l.color3);
        assert!(at(1.0, 1.0).0.abs_diff_eq(l.v0 + l.edge01 + l.edge02, 1e-6));
        let (p, c) = at(0.5, 0.5);
        let mean = (l.color0 + l.color1 + l.color2 + l.color3) / 4.0;
        assert!(c.abs_diff_eq(mean, 1e-6), "{c} vs {mean}");
        assert!(p.abs_diff_eq(l.v0 + 0.5 * (l.edge01 + l.edge02), 1e-6));
    }

    /// Solves p = v0 + u e1 + v e2 for (u, v) (least squares, exact for points in the plane).
    fn uv_of(l: &ParallelogramLight, p: Vec3) -> (Vec2, f32) {
        let d = p - l.v0;
        let (e1, e2) = (l.edge01, l.edge02);
        let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (r1, r2) = (d.dot(e1), d.dot(e2));
        let det = a * c - b * b;
        let uv = Vec2::new((c * r1 - b * r2) / det, (a * r2 - b * r1) / det);
        let off_plane = (d - uv.x * e1 - uv.y * e2).length();
        (uv, off_plane)
    }

    #[test]
    fn parallelogram_samples_inside_and_uniform() {
        let l = parallelogram();
        let s = Sampler::new(2);
        let mut bins = [0u32; 16];
        let n = 20_000u32;
        for i in 0..n {
            let uv = s.get2(i / 4, i % 4, light_dim(1, 0, 3, i % 4));
            let (p, _) = sample_parallelogram_light(&l, uv);
            let (back, off) = uv_of(&l, p);
            assert!(off < 1e-4);
            assert!(
                back.cmpge(Vec2::splat(-1e-5)).all() && back.cmple(Vec2::splat(1.0 + 1e-5)).all()
            );
            let bx = ((back.x * 4.0) as usize).min(3);
            let by = ((back.y * 4.0) as usize).min(3);
            bins[by * 4 + bx] += 1;
        }
        let chi2 = crate::test_util::chi_square(&bins);
        // 15 degrees of freedom: the critical value at p = 1e-4 is about 42.6.
        assert!(chi2 < 42.6, "chi2 {chi2}: {bins:?}");
    }
}
