//! Error of an image against a reference, and least-squares slopes of log-log curves.

use glam::Vec3;

/// Added to `r^2` in the relative MSE so that black reference pixels do not divide by
/// zero. 1e-2 is a common choice in the denoising literature: it matters only where
/// the reference is darker than about 0.1, and it damps those pixels' weight.
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// Error measures of one image against the reference, over every pixel and channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImageError {
    /// Root mean squared error: `sqrt(mean((x - r)^2))`.
    pub rmse: f64,
    /// Relative MSE: `mean((x - r)^2 / (r^2 + REL_MSE_EPSILON))`.
    pub rel_mse: f64,
    /// Mean absolute error: `mean(|x - r|)`.
    pub mae: f64,
}

/// The error of `image` against `reference` (same length, row-major, linear RGB).
///
/// Non-finite values count as 0 so that one bad pixel cannot hide every other.
pub fn image_error(image: &[Vec3], reference: &[Vec3]) -> ImageError {
    let (mut se, mut rel, mut ae) = (0.0f64, 0.0f64, 0.0f64);
    for (x, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let finite = |v: f32| if v.is_finite() { f64::from(v) } else { 0.0 };
            let (x, r) = (finite(x[c]), finite(r[c]));
            let d = x - r;
            se += d * d;
            rel += d * d / (r * r + REL_MSE_EPSILON);
            ae += d.abs();
        }
    }
    let n = (3 * image.len().min(reference.len())).max(1) as f64;
    ImageError {
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
        mae: ae / n,
    }
}

/// The least-squares slope of `log(y)` against `log(x)` over the points with both
/// positive, or `None` with fewer than two such points or no spread in x.
pub fn log_log_slope(points: impl IntoIterator<Item = (f64, f64)>) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .into_iter()
        .filter(|&(x, y)| x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 1e-12).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_errors() {
        let r = [Vec3::new(1.0, 0.0, 2.0), Vec3::ZERO];
        let x = [Vec3::new(1.5, 0.0, 2.0), Vec3::new(0.0, -1.0, 0.0)];
        let e = image_error(&x, &r);
        // Squared differences 0.25 and 1 over 6 values.
        assert!((e.rmse - (1.25f64 / 6.0).sqrt()).abs() < 1e-12);
        assert!((e.mae - 1.5 / 6.0).abs() < 1e-12);
        let rel = 0.25 / (1.0 + REL_MSE_EPSILON) + 1.0 / REL_MSE_EPSILON;
        assert!((e.rel_mse - rel / 6.0).abs() < 1e-9);
        assert_eq!(image_error(&r, &r), ImageError::default());
    }

    #[test]
    fn non_finite_counts_as_zero() {
        let e = image_error(&[Vec3::new(f32::NAN, 0.0, 0.0)], &[Vec3::ZERO]);
        assert_eq!(e, ImageError::default());
    }

    #[test]
    fn slope_of_power_law() {
        let pts = (1..20).map(|i| (f64::from(i), 3.0 * f64::from(i).powf(-0.5)));
        assert!((log_log_slope(pts).unwrap() + 0.5).abs() < 1e-12);
        assert_eq!(log_log_slope([(1.0, 1.0)]), None);
        assert_eq!(log_log_slope([(2.0, 1.0), (2.0, 3.0)]), None);
        assert_eq!(log_log_slope([(0.0, 1.0), (1.0, 0.0)]), None);
    }
}
