//! Sampling linear colour gradients (SPEC "Linear gradient"); the data type is
//! `scene::gradient::Gradient`, since settings hold it.

use glam::Vec3;

pub use crate::scene::gradient::Gradient;

// Sampling is shading, so it lives here, while the data type lives in scene below shade.
impl Gradient {
    /// Samples at `t`: linear between the bracketing components, clamped outside.
    /// An empty gradient (rejected at load) samples black.
    pub fn sample(&self, t: f32) -> Vec3 {
        let c = self.components();
        let Some(first) = c.first() else {
            return Vec3::ZERO;
        };
        // NaN goes to the first colour.
        if t.is_nan() || t <= first.0 {
            return first.1;
        }
        let last = c[c.len() - 1];
        if t >= last.0 {
            return last.1;
        }
        let hi = c.partition_point(|&(ct, _)| ct <= t);
        let (t0, c0) = c[hi - 1];
        let (t1, c1) = c[hi];
        let w = (t - t0) / (t1 - t0);
        c0.lerp(c1, w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(x: f32) -> Vec3 {
        Vec3::splat(x)
    }

    #[test]
    fn one_component_is_constant() {
        let g = Gradient::new(vec![(0.3, Vec3::new(1.0, 2.0, 3.0))]);
        for t in [-10.0, 0.0, 0.3, 0.5, 10.0, f32::NAN] {
            assert_eq!(g.sample(t), Vec3::new(1.0, 2.0, 3.0), "{t}");
        }
    }

    #[test]
    fn two_components_interpolate_and_clamp() {
        let g = Gradient::new(vec![(1.0, grey(10.0)), (3.0, grey(20.0))]);
        assert_eq!(g.sample(1.0), grey(10.0));
        assert_eq!(g.sample(2.0), grey(15.0));
        assert_eq!(g.sample(2.5), grey(17.5));
        assert_eq!(g.sample(3.0), grey(20.0));
        assert_eq!(g.sample(0.0), grey(10.0), "below the range");
        assert_eq!(g.sample(100.0), grey(20.0), "above the range");
    }

    #[test]
    fn unsorted_input_is_sorted() {
        let sorted = Gradient::new(vec![(0.0, grey(0.0)), (0.5, grey(1.0)), (1.0, grey(0.0))]);
        let unsorted = Gradient::new(vec![(1.0, grey(0.0)), (0.0, grey(0.0)), (0.5, grey(1.0))]);
        assert_eq!(sorted, unsorted);
        let ts: Vec<f32> = unsorted.components().iter().map(|c| c.0).collect();
        assert_eq!(ts, [0.0, 0.5, 1.0]);
        assert_eq!(unsorted.sample(0.25), grey(0.5));
        assert_eq!(unsorted.sample(0.75), grey(0.5));
        assert_eq!(unsorted.sample(0.5), grey(1.0));
    }

    #[test]
    fn up_to_eight_components() {
        // Component k at t = k has colour k^2: between k and k + 1 the value is linear.
        for n in 1..=8u32 {
            let mut comps: Vec<(f32, Vec3)> =
                (0..n).map(|k| (k as f32, grey((k * k) as f32))).collect();
            comps.reverse();
            let g = Gradient::new(comps);
            assert_eq!(g.components().len(), n as usize);
            for k in 0..n {
                assert_eq!(g.sample(k as f32), grey((k * k) as f32), "n {n} at {k}");
            }
            for k in 0..n.saturating_sub(1) {
                let mid = (k * k + (k + 1) * (k + 1)) as f32 / 2.0;
                assert_eq!(g.sample(k as f32 + 0.5), grey(mid), "n {n} mid {k}");
            }
            assert_eq!(g.sample(-1.0), grey(0.0));
            let last = ((n - 1) * (n - 1)) as f32;
            assert_eq!(g.sample(n as f32 + 5.0), grey(last));
        }
    }

    #[test]
    fn default_comparison_gradient() {
        let g = Gradient::default_comparison();
        assert_eq!(g.sample(-1.0), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(g.sample(0.0), Vec3::splat(0.1));
        assert_eq!(g.sample(1.0), Vec3::new(0.0, 1.0, 0.0));
        assert!(g.sample(0.5).abs_diff_eq(Vec3::new(0.05, 0.55, 0.05), 1e-6));
    }

    #[test]
    fn duplicate_t_does_not_divide_by_zero() {
        // A step: two components at the same t.
        let g = Gradient::new(vec![
            (0.0, grey(0.0)),
            (0.5, grey(1.0)),
            (0.5, grey(2.0)),
            (1.0, grey(3.0)),
        ]);
        for t in [0.25, 0.5, 0.75] {
            assert!(g.sample(t).is_finite(), "{t}");
        }
        assert_eq!(g.sample(0.25), grey(0.5));
        assert_eq!(g.sample(0.75), grey(2.5));
    }

    #[test]
    fn empty_is_black() {
        assert_eq!(Gradient::new(Vec::new()).sample(0.5), Vec3::ZERO);
    }
}
