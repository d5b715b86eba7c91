//! `glint converge`: error against a reference after every pass, for several
//! configurations of a scene under the same budget, as a table, a CSV and a plot.
//!
//! Each configuration renders progressively (sample index after sample index, as
//! [`Renderer::render`] does) without the scene's `pixel_samples` as a stop: only the
//! budget (`time`, `max_spp`) stops it. The pixel pattern still follows the settings:
//! stratified with `pixel_samples = n` uses a `k x k` grid (`k = round(sqrt n)`) and
//! sample indices past `k*k` start a new grid with fresh jitter. A stratified image
//! is only a complete stratification after whole grids, so stratified configurations
//! are measured (and can stop) only every `k*k` passes; uniform ones every pass.

pub mod plot;
pub mod reference;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::error::{GlintError, Result};
use crate::film::estimate::ErrorEstimate;
use crate::film::metrics::{ImageError, image_error, log_log_slope};
use crate::film::write_atomically;
use crate::render::{Overrides, Renderer};
use crate::sampling::{pixel_mode, samples_taken};
use crate::scene::format::SceneFile;
use crate::scene::{PixelSampling, parse_scene};
use reference::{Reference, ReferenceOrigin, cached_reference, read_reference};

/// Where the reference image comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReferenceSource {
    /// An image file (EXR) of the render's size.
    File(PathBuf),
    /// A render at this many samples per pixel, cached beside the scene.
    Render {
        /// Requested samples per pixel (rounded to a square: the reference is stratified).
        spp: u32,
    },
}

/// Everything `glint converge` needs.
#[derive(Clone, Debug)]
pub struct ConvergeOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// Changes applied to the scene before every configuration and the reference.
    pub overrides: Overrides,
    /// The reference.
    pub reference: ReferenceSource,
    /// Render-time budget per configuration (error measurement excluded).
    pub time: Option<Duration>,
    /// Samples per pixel at which a configuration stops.
    pub max_spp: Option<u32>,
    /// Settings to compare: the configurations are the cross product of the values.
    pub compare: Vec<(String, Vec<String>)>,
    /// CSV output.
    pub csv: Option<PathBuf>,
    /// PNG plot output.
    pub plot: Option<PathBuf>,
    /// Stops the run (after the region in flight) when set; results so far are kept.
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// The columns of the CSV, in order.
pub const CSV_COLUMNS: [&str; 11] = [
    "configuration",
    "pass",
    "spp",
    "seconds",
    "rays",
    "rmse",
    "rel_mse",
    "mae",
    "true_rmse",
    "est_rmse",
    "est_rel_mse",
];

/// One measured pass of one configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassRecord {
    /// 1-based index of the measured pass (counts grids for stratified configurations).
    pub pass: u32,
    /// Samples per pixel so far.
    pub spp: u32,
    /// Render seconds so far (prepare included, error measurement excluded).
    pub seconds: f64,
    /// Rays traced so far.
    pub rays: u64,
    /// Error against the reference.
    pub error: ImageError,
    /// The render's own estimate of its error, without the reference.
    pub estimate: Option<ErrorEstimate>,
}

/// The passes of one configuration.
#[derive(Clone, Debug)]
pub struct Curve {
    /// `key=value` pairs that define the configuration (empty: the scene as is).
    pub settings: Vec<(String, String)>,
    /// Samples per measured pass (1, or `k*k` for stratified).
    pub spp_per_pass: u32,
    /// Measured passes, in order.
    pub passes: Vec<PassRecord>,
    /// The reference's own estimated MSE (0 when unknown), part of every measured MSE.
    pub reference_mse: f64,
}

impl Curve {
    /// A label such as `pixel_sampling=uniform, shadow_samples=4`.
    pub fn label(&self) -> String {
        if self.settings.is_empty() {
            return "scene settings".into();
        }
        let parts: Vec<String> = self
            .settings
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        parts.join(", ")
    }

    /// Fitted slope of log RMSE against log seconds.
    pub fn slope_time(&self) -> Option<f64> {
        log_log_slope(self.passes.iter().map(|p| (p.seconds, p.error.rmse)))
    }

    /// Fitted slope of log RMSE against log spp.
    pub fn slope_spp(&self) -> Option<f64> {
        log_log_slope(self.passes.iter().map(|p| (f64::from(p.spp), p.error.rmse)))
    }

    /// The true RMSE of a pass: the measured one less the reference's own error
    /// (measured MSE = true MSE + reference MSE, the two being independent).
    pub fn true_rmse(&self, pass: &PassRecord) -> f64 {
        (pass.error.rmse.powi(2) - self.reference_mse)
            .max(0.0)
            .sqrt()
    }

    /// The ratio of the estimated to the true RMSE at the last measured pass.
    pub fn estimate_ratio(&self) -> Option<f64> {
        let last = self.passes.last()?;
        let e = last.estimate?;
        let truth = self.true_rmse(last);
        (truth > 0.0).then(|| e.rmse / truth)
    }
}

/// What a converge run measured.
#[derive(Clone, Debug)]
pub struct ConvergeReport {
    /// Where the reference came from.
    pub reference: ReferenceOrigin,
    /// One curve per configuration.
    pub curves: Vec<Curve>,
    /// Whether the interrupt flag cut the run short.
    pub interrupted: bool,
    /// Notes for the user (e.g. settings that cannot converge).
    pub warnings: Vec<String>,
}

/// The configurations: the cross product of the compared values, in flag order
/// (the last flag varies fastest). No flag gives one empty configuration.
pub fn configurations(compare: &[(String, Vec<String>)]) -> Vec<Vec<(String, String)>> {
    let mut configs = vec![Vec::new()];
    for (key, values) in compare {
        configs = configs
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push((key.clone(), v.clone()));
                    c
                })
            })
            .collect();
    }
    configs
}

/// Quotes a CSV field when it needs it (RFC 4180).
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// The CSV text: a header of [`CSV_COLUMNS`] and one row per (configuration, pass).
pub fn csv_text(curves: &[Curve]) -> String {
    let mut out = CSV_COLUMNS.join(",");
    out.push('\n');
    for c in curves {
        let label = csv_field(&c.label());
        for p in &c.passes {
            let estimate = p.estimate.map_or_else(
                || ",".to_owned(),
                |e| format!("{:.9e},{:.9e}", e.rmse, e.rel_mse),
            );
            let _ = writeln!(
                out,
                "{label},{},{},{:.6},{},{:.9e},{:.9e},{:.9e},{:.9e},{estimate}",
                p.pass,
                p.spp,
                p.seconds,
                p.rays,
                p.error.rmse,
                p.error.rel_mse,
                p.error.mae,
                c.true_rmse(p)
            );
        }
    }
    out
}

/// The scene with the overrides, then the configuration's settings, applied.
fn configured_scene(
    options: &ConvergeOptions,
    scene_text: &str,
    settings: &[(String, String)],
) -> Result<SceneFile> {
    let mut file = parse_scene(scene_text, &options.scene)?;
    options.overrides.apply(&mut file)?;
    for (k, v) in settings {
        file.settings.set(k, v).map_err(GlintError::Setting)?;
    }
    Ok(file)
}

/// Renders one configuration pass by pass until the budget is spent.
fn run_configuration(
    options: &ConvergeOptions,
    scene_text: &str,
    settings: &[(String, String)],
    reference: &Reference,
    log: &mut (dyn FnMut(&str) + Send),
) -> Result<(Curve, Vec<String>)> {
    let file = configured_scene(options, scene_text, settings)?;
    let mut renderer = Renderer::from_scene(&file, &options.scene)?;
    if let Some(flag) = &options.interrupt {
        renderer.set_interrupt(flag.clone());
    }
    let camera = renderer.camera().ok_or(GlintError::NoCamera)?;
    if (camera.width, camera.height) != (reference.width, reference.height) {
        return Err(GlintError::Reference(format!(
            "the reference is {}x{} but the render is {}x{}",
            reference.width, reference.height, camera.width, camera.height
        )));
    }
    let s = renderer.settings().clone();
    let mut curve = Curve {
        settings: settings.to_vec(),
        spp_per_pass: match pixel_mode(&s) {
            PixelSampling::Uniform => 1,
            PixelSampling::Stratified => samples_taken(s.pixel_samples, s.pixel_sampling),
        },
        passes: Vec::new(),
        reference_mse: reference.mse.unwrap_or(0.0),
    };
    let mut warnings = Vec::new();
    if s.pixel_samples <= 1 {
        warnings.push(format!(
            "{}: pixel_samples = {} samples every pixel at its centre, so the error \
             stops falling at the aliasing of the edges (set pixel_samples >= 2)",
            curve.label(),
            s.pixel_samples
        ));
    }
    // A stratified grid larger than the spp budget would never be measured.
    if let Some(max) = options.max_spp {
        curve.spp_per_pass = curve.spp_per_pass.min(max.max(1));
    }
    let interrupted = |r: &Renderer| r.interrupted();
    let mut seconds = 0.0;
    let mut sample = 0u32;
    loop {
        let start = Instant::now();
        renderer.render_pass(sample, &mut |_| {})?;
        seconds += start.elapsed().as_secs_f64();
        if interrupted(&renderer) {
            break;
        }
        sample += 1;
        if !sample.is_multiple_of(curve.spp_per_pass) {
            continue;
        }
        let error = image_error(&renderer.film().image(), &reference.pixels);
        curve.passes.push(PassRecord {
            pass: sample / curve.spp_per_pass,
            spp: sample,
            seconds,
            rays: renderer.stats().rays.total(),
            error,
            estimate: renderer.error_estimate(),
        });
        let out_of_time = options.time.is_some_and(|t| seconds >= t.as_secs_f64());
        let out_of_spp = options
            .max_spp
            .is_some_and(|m| sample.saturating_add(curve.spp_per_pass) > m);
        if out_of_time || out_of_spp || sample == u32::MAX {
            break;
        }
    }
    match curve.passes.last() {
        Some(p) => log(&format!(
            "{}: {} spp in {:.2} s, RMSE {:.4e}",
            curve.label(),
            p.spp,
            p.seconds,
            p.error.rmse
        )),
        None => log(&format!("{}: no complete pass", curve.label())),
    }
    Ok((curve, warnings))
}

/// Runs every configuration, writes the CSV and plot if asked, and reports.
pub fn run(
    options: &ConvergeOptions,
    log: &mut (dyn FnMut(&str) + Send),
) -> Result<ConvergeReport> {
    if options.time.is_none() && options.max_spp.is_none() {
        return Err(GlintError::Options(
            "converge needs a budget: a time or a number of samples per pixel".into(),
        ));
    }
    if options.max_spp == Some(0) {
        return Err(GlintError::Options(
            "the samples per pixel budget must be at least 1".into(),
        ));
    }
    for (key, values) in &options.compare {
        if values.is_empty() {
            return Err(GlintError::Options(format!(
                "no values to compare for {key}"
            )));
        }
    }
    if let Some(path) = &options.plot {
        check_png(path)?;
    }
    let scene_text = std::fs::read_to_string(&options.scene).map_err(|source| GlintError::Io {
        path: options.scene.clone(),
        source,
    })?;
    let configs = configurations(&options.compare);
    // Reject a bad key or value before the (possibly long) reference render.
    for settings in &configs {
        let file = configured_scene(options, &scene_text, settings)?;
        crate::scene::load::validate_settings(&file.settings, &options.scene)?;
    }
    let (reference, origin) = match &options.reference {
        ReferenceSource::File(path) => (
            read_reference(path)?,
            ReferenceOrigin::Supplied(path.clone()),
        ),
        ReferenceSource::Render { spp } => cached_reference(
            &options.scene,
            &options.overrides,
            *spp,
            options.interrupt.clone(),
            log,
        )?,
    };
    if let ReferenceOrigin::Cached(path) = &origin {
        log(&format!("reference: {} (cached)", path.display()));
    }
    let mut curves = Vec::new();
    let mut warnings = Vec::new();
    let stop = || {
        options
            .interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    };
    for settings in &configs {
        if stop() {
            break;
        }
        let (curve, w) = run_configuration(options, &scene_text, settings, &reference, log)?;
        curves.push(curve);
        warnings.extend(w);
    }
    for w in &warnings {
        log(&format!("warning: {w}"));
    }
    if let Some(path) = &options.csv {
        write_atomically(path, csv_text(&curves).as_bytes())?;
    }
    if let Some(path) = &options.plot {
        plot::write_plot(path, &curves)?;
    }
    Ok(ConvergeReport {
        reference: origin,
        curves,
        interrupted: stop(),
        warnings,
    })
}

/// Fails before any render on a plot name that is not `.png`.
fn check_png(path: &Path) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str());
    if ext.is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        Ok(())
    } else {
        Err(GlintError::Output {
            path: path.to_owned(),
            message: "the plot is a PNG (use a .png name)".into(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_product_in_flag_order() {
        let c = configurations(&[
            ("a".into(), vec!["1".into(), "2".into()]),
            ("b".into(), vec!["x".into(), "y".into(), "z".into()]),
        ]);
        assert_eq!(c.len(), 6);
        assert_eq!(
            c[0],
            vec![("a".into(), "1".into()), ("b".into(), "x".into())]
        );
        assert_eq!(
            c[5],
            vec![("a".into(), "2".into()), ("b".into(), "z".into())]
        );
        assert_eq!(configurations(&[]), vec![Vec::new()]);
    }

    #[test]
    fn csv_quotes_labels_with_commas() {
        assert_eq!(csv_field("a=1, b=2"), "\"a=1, b=2\"");
        assert_eq!(csv_field("plain"), "plain");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
    }
}
