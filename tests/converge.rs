//! `glint converge`: error against a reference per pass, the CSV, the plot and the
//! reference cache, on small scenes with an area light.

mod common;

use std::path::Path;

use common::*;

use glint::converge::{
    CSV_COLUMNS, ConvergeOptions, ConvergeReport, ReferenceSource, reference::ReferenceOrigin, run,
};
use glint::{Overrides, Renderer};

/// The shared area-light scene at 32x32; `settings` is spliced into its settings.
fn scene_text(settings: &str) -> String {
    sphere_under_area_light(32, &format!("reflections: false, {settings}"))
}

fn options(scene: &Path, reference_spp: u32, max_spp: u32) -> ConvergeOptions {
    ConvergeOptions {
        scene: scene.to_owned(),
        overrides: Overrides::default(),
        reference: ReferenceSource::Render { spp: reference_spp },
        time: None,
        max_spp: Some(max_spp),
        compare: Vec::new(),
        csv: None,
        plot: None,
        interrupt: None,
    }
}

fn run_quiet(o: &ConvergeOptions) -> ConvergeReport {
    run(o, &mut |_| {}).unwrap()
}

fn rmse_at(report: &ConvergeReport, curve: usize, spp: u32) -> f64 {
    let c = &report.curves[curve];
    c.passes
        .iter()
        .find(|p| p.spp == spp)
        .unwrap_or_else(|| panic!("{}: no pass at {spp} spp", c.label()))
        .error
        .rmse
}

#[test]
fn rmse_falls_with_spp_on_an_area_light_scene() {
    let tmp = scene_dir(&scene_text(
        "pixel_samples: 16, pixel_sampling: uniform, shadow_samples: 4, seed: 3",
    ));
    let dir = tmp.path();
    let report = run_quiet(&options(&dir.join("scene.ron"), 1024, 64));
    let c = &report.curves[0];
    assert_eq!(c.passes.len(), 64, "uniform: one measured pass per sample");
    let levels: Vec<f64> = [1, 4, 16, 64].map(|s| rmse_at(&report, 0, s)).to_vec();
    // Monte Carlo: 4x the samples halves the RMSE in expectation; allow 0.7.
    for w in levels.windows(2) {
        assert!(w[1] < 0.7 * w[0], "RMSE at 1/4/16/64 spp: {levels:?}");
    }
    let slope = c.slope_spp().unwrap();
    assert!((-0.65..-0.35).contains(&slope), "slope {slope}");
    // Time, rays and spp only grow.
    for w in c.passes.windows(2) {
        assert!(w[1].seconds >= w[0].seconds && w[1].rays > w[0].rays && w[1].spp > w[0].spp);
    }
}

#[test]
fn stratified_beats_uniform_at_equal_spp() {
    let tmp = scene_dir(&scene_text("pixel_samples: 16, shadow_samples: 16"));
    let dir = tmp.path();
    let mut o = options(&dir.join("scene.ron"), 1024, 16);
    // Four seeds per pattern: one 32x32 image's RMSE hinges on a few edge pixels
    // (single-seed RMSE ratios measured 0.56-0.85); the summed MSE is steadier.
    let seeds: Vec<String> = (1..=4).map(|s| s.to_string()).collect();
    o.compare = vec![
        (
            "pixel_sampling".into(),
            vec!["uniform".into(), "stratified".into()],
        ),
        ("seed".into(), seeds),
    ];
    let report = run_quiet(&o);
    assert_eq!(report.curves.len(), 8);
    // Stratified is measured only after its whole 4x4 grid.
    assert_eq!(report.curves[4].spp_per_pass, 16);
    assert_eq!(report.curves[4].passes.len(), 1);
    let mse = |range: std::ops::Range<usize>| -> f64 {
        range.map(|i| rmse_at(&report, i, 16).powi(2)).sum()
    };
    let (uniform, stratified) = (mse(0..4), mse(4..8));
    // Measured ratio about 0.4: edges converge faster when stratified.
    assert!(
        stratified < 0.7 * uniform,
        "summed MSE: stratified {stratified} vs uniform {uniform}"
    );
}

#[test]
fn csv_plot_and_reference_cache() {
    let text = scene_text("pixel_samples: 4, shadow_samples: 2, seed: 5");
    let tmp = scene_dir(&text);
    let dir = tmp.path();
    let scene = dir.join("scene.ron");
    let mut o = options(&scene, 16, 4);
    o.compare = vec![(
        "pixel_sampling".into(),
        vec!["uniform".into(), "stratified".into()],
    )];
    o.csv = Some(dir.join("out.csv"));
    o.plot = Some(dir.join("out.png"));
    let first = run_quiet(&o);
    let ReferenceOrigin::Rendered(cache) = &first.reference else {
        panic!("first run must render the reference: {:?}", first.reference);
    };
    assert!(
        cache.starts_with(dir.join(".glint-cache")),
        "{}",
        cache.display()
    );

    let csv = std::fs::read_to_string(dir.join("out.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], CSV_COLUMNS.join(","));
    let passes: usize = first.curves.iter().map(|c| c.passes.len()).sum();
    // Uniform: 4 passes of 1 spp; stratified: 1 pass of its 2x2 grid.
    assert_eq!(passes, 5);
    assert_eq!(lines.len(), 1 + passes);
    for line in &lines[1..] {
        // The label is quoted (it holds no comma here, so it is bare): 8 fields.
        assert_eq!(line.split(',').count(), CSV_COLUMNS.len(), "{line}");
    }
    assert!(
        lines[5].starts_with("pixel_sampling=stratified,1,4,"),
        "{}",
        lines[5]
    );
    let plot = image::open(dir.join("out.png")).unwrap();
    assert!(plot.width() >= 800 && plot.height() >= 500);

    // Nothing changed: the cache is reused, with the same pixels.
    let stamp = std::fs::metadata(cache).unwrap().modified().unwrap();
    let second = run_quiet(&o);
    assert_eq!(second.reference, ReferenceOrigin::Cached(cache.clone()));
    assert_eq!(std::fs::metadata(cache).unwrap().modified().unwrap(), stamp);
    assert_eq!(
        first.curves[0].passes[3].error, second.curves[0].passes[3].error,
        "same reference, same passes, same error"
    );

    // The scene changed: a new reference is rendered.
    std::fs::write(&scene, text.replace("(0.3, 0.3, 0.3)", "(0.5, 0.3, 0.3)")).unwrap();
    let third = run_quiet(&o);
    match &third.reference {
        ReferenceOrigin::Rendered(p) => assert_ne!(p, cache),
        other => panic!("changed scene must re-render: {other:?}"),
    }
}

#[test]
fn supplied_reference_of_the_wrong_size_is_a_clear_error() {
    let tmp = scene_dir(&scene_text("pixel_samples: 4"));
    let dir = tmp.path();
    let reference = dir.join("ref.exr");
    glint::film::write_image(
        &reference,
        8,
        8,
        &[glam::Vec3::ONE; 64],
        glint::film::Encoding::Linear,
    )
    .unwrap();
    let mut o = options(&dir.join("scene.ron"), 16, 2);
    o.reference = ReferenceSource::File(reference);
    let err = run(&o, &mut |_| {}).unwrap_err().to_string();
    assert!(err.contains("8x8") && err.contains("32x32"), "{err}");
}

#[test]
fn supplied_reference_equal_to_the_render_gives_zero_error() {
    let text = scene_text("pixel_samples: 4, seed: 2");
    let tmp = scene_dir(&text);
    let dir = tmp.path();
    let scene = dir.join("scene.ron");
    // The 4-spp render itself, as an EXR: the last pass must match it exactly.
    let mut r = Renderer::from_file(&scene, &Overrides::default()).unwrap();
    r.render(None, &mut |_| {}).unwrap();
    let reference = dir.join("ref.exr");
    let film = r.film();
    glint::film::write_image(
        &reference,
        film.width,
        film.height,
        &film.image(),
        glint::film::Encoding::Linear,
    )
    .unwrap();
    let mut o = options(&scene, 16, 4);
    o.reference = ReferenceSource::File(reference.clone());
    let report = run_quiet(&o);
    assert_eq!(report.reference, ReferenceOrigin::Supplied(reference));
    let last = report.curves[0].passes.last().unwrap();
    assert_eq!(last.spp, 4);
    assert_eq!(last.error.rmse, 0.0);
    assert!(report.curves[0].passes[0].error.rmse > 0.0);
}

/// A 4096-spp reference takes minutes: its render reports how far it is and the time left.
#[test]
fn the_reference_render_reports_progress_and_time_left() {
    let tmp = scene_dir(&scene_text("pixel_samples: 4, shadow_samples: 1, seed: 5"));
    let mut lines = Vec::new();
    run(&options(&tmp.path().join("scene.ron"), 64, 1), &mut |l| {
        lines.push(l.to_owned())
    })
    .unwrap();
    let progress: Vec<_> = lines
        .iter()
        .filter(|l| l.starts_with("reference: ") && l.contains("% done") && l.contains("left"))
        .collect();
    assert!(progress.len() >= 5, "{lines:#?}");
    let done = lines.iter().position(|l| l.starts_with("reference done"));
    let last = lines.iter().rposition(|l| l.starts_with("reference: "));
    assert!(last < done, "{lines:#?}");
}
