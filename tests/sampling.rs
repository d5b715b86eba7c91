//! Samplers and error estimates end to end: Sobol' renders are unbiased, the film's
//! variance estimate matches closed forms, and `--target-error` stops where it says.

mod common;

use std::time::Duration;

use common::*;
use glam::DVec3;
use glint::film::estimate::EstimateMethod;
use glint::film::metrics::image_error;
use glint::render::{Ended, MIN_TARGET_SPP, StopRule};

/// A wall at z = 0 seen through one pixel at its centre from (2, 0, 3), lit with shading
/// off by a segment light from (-1, 0, 2) to (1, 0, 2) of colour 1; an occluder in the
/// plane z = 1 covering x < 0 hides exactly the half s < 1/2 of the light from the
/// origin. A light sample is then 1 or 0 with probability 1/2 each: variance 1/4.
fn half_shadow(settings: &str) -> String {
    format!(
        r#"(
    camera: (position: (2, 0, 3), look_at: (0, 0, 0), fov_y: 0.001, width: 1, height: 1),
    settings: (shading: false, reflections: false, {settings}),
    materials: {{ "white": (kd: (1, 1, 1)) }},
    entities: [
        Mesh((material: Some("white"), geometry: Parallelogram(origin: (-5, -5, 0),
            edge_u: (10, 0, 0), edge_v: (0, 10, 0)))),
        Mesh((material: Some("white"), geometry: Parallelogram(origin: (-5, -5, 1),
            edge_u: (5, 0, 0), edge_v: (0, 10, 0)))),
        SegmentLight((endpoint0: (-1, 0, 2), endpoint1: (1, 0, 2),
            color0: (1, 1, 1), color1: (1, 1, 1))),
    ],
)"#
    )
}

/// The sample variance (not of the mean) of the single pixel's red channel.
fn sample_variance(settings: &str) -> (f64, f64) {
    let r = render(&half_shadow(settings));
    let film = r.film();
    let n = f64::from(film.count[0]);
    let var_of_mean = film
        .pixel_variance(0, EstimateMethod::Moments)
        .expect("enough samples");
    (film.sum[0].x / n, var_of_mean.x * n)
}

#[test]
fn half_shadowed_pixel_has_the_analytic_variance() {
    // One light sample per pass: Bernoulli(1/2), variance 1/4. With 400 passes the
    // sample variance is p(1 - p) n / (n - 1) for the observed p, within 0.25 +- 0.003.
    let (mean, var) = sample_variance("pixel_samples: 400, shadow_samples: 1");
    assert!((mean - 0.5).abs() < 0.1, "mean {mean}");
    assert!((var - 0.25).abs() < 0.004, "variance {var}");
    // Four independent light samples: Binomial(4, 1/2) / 4, variance 1/16.
    let (_, var) = sample_variance("pixel_samples: 400, shadow_samples: 4");
    assert!((var - 1.0 / 16.0).abs() < 0.012, "variance {var}");
    // Four stratified light samples put two in each half of the light, every pass:
    // each pass is exactly 1/2 and the variance is exactly 0.
    let (mean, var) = sample_variance("pixel_samples: 64, shadow_samples: 4, sampler: stratified");
    assert_eq!((mean, var), (0.5, 0.0));
}

#[test]
fn constant_scene_has_zero_estimated_error() {
    // Shading off and a point light: every sample of every pixel is kd * light.
    for sampler in ["independent", "stratified", "sobol"] {
        let text = format!(
            r#"(
    camera: (position: (0, 0, 3), look_at: (0, 0, 0), fov_y: 20, width: 5, height: 5),
    settings: (shading: false, pixel_samples: 8, sampler: {sampler}),
    materials: {{ "grey": (kd: (0.3, 0.6, 0.9)) }},
    entities: [
        {},
        PointLight((position: (0, 0, 2), color: (1, 1, 1))),
    ],
)"#,
            quad(0.0, "grey")
        );
        let r = render(&text);
        let estimate = r.error_estimate().expect("8 samples per pixel");
        assert_eq!((estimate.rmse, estimate.rel_mse), (0.0, 0.0), "{sampler}");
    }
}

/// The mean over pixels and channels of a render of the area-light scene.
fn image_mean(sampler: &str, seed: u64) -> f64 {
    let r = render(&sphere_under_area_light(
        8,
        &format!("pixel_samples: 4, shadow_samples: 2, sampler: {sampler}, seed: {seed}"),
    ));
    let image = r.film().image();
    image
        .iter()
        .map(|p| f64::from(p.element_sum()))
        .sum::<f64>()
        / (3 * image.len()) as f64
}

/// Mean and standard error of `f` over seeds 0..n.
fn mean_and_error(n: u64, f: impl Fn(u64) -> f64) -> (f64, f64) {
    let xs: Vec<f64> = (0..n).map(f).collect();
    let mean = xs.iter().sum::<f64>() / n as f64;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
    (mean, (var / n as f64).sqrt())
}

#[test]
fn sobol_and_stratified_renders_are_unbiased() {
    let (independent, se_i) = mean_and_error(40, |s| image_mean("independent", s));
    for sampler in ["sobol", "stratified"] {
        let (mean, se) = mean_and_error(40, |s| image_mean(sampler, s));
        let tolerance = 4.0 * (se * se + se_i * se_i).sqrt();
        assert!(
            (mean - independent).abs() < tolerance,
            "{sampler}: {mean} against independent {independent} (tolerance {tolerance})"
        );
    }
}

#[test]
fn sobol_renders_are_the_same_for_any_pass_split() {
    // Pass by pass (as progressive renders and converge run) equals one fixed render.
    let text = sphere_under_area_light(12, "pixel_samples: 6, sampler: sobol, seed: 3");
    let fixed = render(&text);
    let mut stepwise = load(&text);
    for sample in 0..6 {
        stepwise.render_pass(sample, &mut |_| {}).unwrap();
    }
    assert_eq!(fixed.film(), stepwise.film());
}

#[test]
fn low_discrepancy_samplers_are_bit_identical_across_thread_counts() {
    for sampler in ["sobol", "stratified"] {
        let text = sphere_under_area_light(
            40,
            &format!("pixel_samples: 4, shadow_samples: 3, sampler: {sampler}"),
        );
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| render(&text).film().clone())
        };
        assert!(run(1) == run(2), "{sampler}: 1- and 2-thread films differ");
    }
}

#[test]
fn the_estimate_is_within_a_quarter_of_the_true_rmse_at_16_spp() {
    let scene = |sampler: &str, spp: u32, seed: u64| {
        render(&sphere_under_area_light(
            32,
            &format!(
                "pixel_samples: {spp}, pixel_sampling: uniform, shadow_samples: 2, sampler: {sampler}, seed: {seed}"
            ),
        ))
    };
    let reference = scene("sobol", 512, 99);
    let reference_mse = reference.error_estimate().unwrap().rmse.powi(2);
    for sampler in ["independent", "stratified", "sobol"] {
        // Four seeds: the MSE of one small image varies by about 10% (a few edge
        // pixels carry much of it).
        let (mut estimated, mut measured) = (0.0, 0.0);
        for seed in 1..=4 {
            let r = scene(sampler, 16, seed);
            estimated += r.error_estimate().unwrap().rmse.powi(2);
            measured += image_error(&r.film().image(), &reference.film().image())
                .rmse
                .powi(2);
        }
        let ratio = (estimated / (measured - 4.0 * reference_mse)).sqrt();
        eprintln!("{sampler}: estimate / truth = {ratio:.3}");
        assert!(
            (0.75..=1.25).contains(&ratio),
            "{sampler}: estimate / truth = {ratio}"
        );
    }
}

/// Renders the area-light scene with `sampler` until `rule` says stop.
fn render_until(
    sampler: &str,
    spp: u32,
    rule: &StopRule,
) -> (glint::RenderSummary, glint::Renderer) {
    let mut r = load(&sphere_under_area_light(
        16,
        &format!(
            "pixel_samples: {spp}, pixel_sampling: uniform, shadow_samples: 1, sampler: {sampler}, seed: 5"
        ),
    ));
    let summary = r.render_until(rule, &mut |_| {}).unwrap();
    (summary, r)
}

#[test]
fn target_error_stops_at_the_first_check_that_meets_it() {
    for (sampler, step) in [("independent", 1), ("sobol", 2)] {
        // The estimate at 16 spp, halved in variance: reached at about 32 spp.
        let (at16, _) = render_until(sampler, 16, &StopRule::default());
        let target = at16.error.expect("an estimate").rmse / 2f64.sqrt();
        let rule = StopRule {
            target_rmse: Some(target),
            ..StopRule::default()
        };
        let (summary, r) = render_until(sampler, 4, &rule);
        assert_eq!(summary.ended, Ended::Target, "{sampler}");
        assert!(summary.to_string().contains("ended by the error target"));
        let m = summary.samples;
        assert!(
            m > 16 && m.is_multiple_of(step),
            "{sampler}: stopped at {m}"
        );
        assert!(summary.error.unwrap().rmse <= target);
        // The previous check had not met it, and the image is a fixed render of m spp.
        let (before, _) = render_until(sampler, m - step, &StopRule::default());
        assert!(m - step < MIN_TARGET_SPP || before.error.unwrap().rmse > target);
        let (fixed, fixed_r) = render_until(sampler, m, &StopRule::default());
        assert_eq!(fixed.samples, m);
        assert_eq!(r.film(), fixed_r.film(), "{sampler}: {m} spp");
    }
}

#[test]
fn time_ends_a_render_whose_target_is_out_of_reach() {
    let rule = StopRule {
        time: Some(Duration::from_millis(300)),
        target_rmse: Some(1e-12),
        target_rel_error: None,
    };
    let (summary, r) = render_until("sobol", 4, &rule);
    assert_eq!(summary.ended, Ended::Time);
    assert!(summary.samples > 4, "went past pixel_samples");
    assert!(r.film().m2.iter().any(|&m| m != DVec3::ZERO));
}
