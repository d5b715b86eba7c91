//! The render driver: loads a scene into a `World`, runs the schedules, reports.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use bevy_ecs::name::Name;
use bevy_ecs::prelude::*;

use crate::error::{GlintError, Result};
use crate::film::Film;
use crate::film::estimate::{ErrorEstimate, EstimateMethod};
use crate::film::part::{Crop, Part, PartInfo, crop_film};
use crate::memory;
use crate::sampling::{pixel_mode, samples_per_pixel};
use crate::scene::format::{
    CameraDesc, EntityDesc, GeometryDesc, MeshDesc, PointLightDesc, SceneFile, TransformDesc,
};
use crate::scene::model::{DEFAULT_LIGHT_NAME, SceneFormat, spawn_model};
use crate::scene::{
    Camera, Mesh, MeshData, PixelSampling, PointLight, SamplerKind, SceneSource, Settings,
    read_scene, spawn_scene,
};
use crate::schedule::{PassControl, add_render_schedules, run_pass, run_passes, run_prepare};
use crate::stats::RenderStats;
use crate::trace::geometry::SceneGeometry;
use crate::trace::lights::Lights;
use crate::trace::materials::Materials;
use crate::trace::plan::RenderPlan;

pub use crate::scene::Overrides;

/// What a finished render did.
#[derive(Clone, Debug)]
pub struct RenderSummary {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel taken.
    pub samples: u32,
    /// Wall time of the whole render (prepare and passes).
    pub seconds: f64,
    /// Wall time of the prepare stage (tables, texture decoding, BVH builds).
    pub prepare_seconds: f64,
    /// Statistics of the run.
    pub stats: RenderStats,
    /// Choices the loader made (automatic camera, default light), shown after the numbers.
    pub notes: Vec<String>,
    /// Whether the interrupt flag stopped the render before its last pass.
    pub interrupted: bool,
    /// The film's estimate of its own error (`None` below two samples per pixel).
    pub error: Option<ErrorEstimate>,
    /// What ended the run.
    pub ended: Ended,
}

/// What ended a render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Ended {
    /// Every sample of `pixel_samples` was taken.
    #[default]
    AllSamples,
    /// The time budget was spent.
    Time,
    /// The error estimate reached the target.
    Target,
    /// The interrupt flag (Ctrl-C).
    Interrupt,
}

/// When a render stops: at `pixel_samples` or `time`; with a target, the passes go on
/// past `pixel_samples` until the error estimate reaches it or `time` is spent.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StopRule {
    /// Time budget (checked after each pass).
    pub time: Option<Duration>,
    /// Estimated RMSE at which to stop.
    pub target_rmse: Option<f64>,
    /// Estimated relative RMSE, `sqrt(relMSE)`, at which to stop.
    pub target_rel_error: Option<f64>,
}

impl StopRule {
    /// Whether `estimate` meets every target given (and there is a target).
    pub fn reached(&self, estimate: Option<&ErrorEstimate>) -> bool {
        if self.target_rmse.is_none() && self.target_rel_error.is_none() {
            return false;
        }
        estimate.is_some_and(|e| {
            self.target_rmse.is_none_or(|t| e.rmse <= t)
                && self.target_rel_error.is_none_or(|t| e.rel_mse.sqrt() <= t)
        })
    }
}

/// A target is never judged on fewer samples per pixel: below this the estimate is too
/// noisy to trust, and stopping on a lucky low one would be a biased choice.
pub const MIN_TARGET_SPP: u32 = 8;

impl RenderSummary {
    /// Wall time of the passes alone.
    pub fn trace_seconds(&self) -> f64 {
        (self.seconds - self.prepare_seconds).max(0.0)
    }

    /// Rays traced per second of tracing (the prepare stage excluded), in millions.
    pub fn mrays_per_second(&self) -> f64 {
        self.stats.rays.total() as f64 / self.trace_seconds().max(1e-9) / 1e6
    }
}

impl std::fmt::Display for RenderSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = &self.stats.rays;
        write!(
            f,
            "{}x{}, {} spp, {:.2} s ({:.2} s prepare, {:.2} s trace), rays: {} camera, {} shadow, {} reflection, {} pass-through, {:.2} Mrays/s",
            self.width,
            self.height,
            self.samples,
            self.seconds,
            self.prepare_seconds,
            self.trace_seconds(),
            r.camera,
            r.shadow,
            r.reflection,
            r.pass_through,
            self.mrays_per_second()
        )?;
        if self.stats.nonfinite_samples > 0 {
            write!(
                f,
                ", {} non-finite samples dropped",
                self.stats.nonfinite_samples
            )?;
        }
        if let Some(e) = &self.error {
            write!(f, "; estimated error: {e}")?;
        }
        match self.ended {
            Ended::AllSamples => {}
            Ended::Time => write!(f, "; ended by the time budget")?,
            Ended::Target => write!(f, "; ended by the error target")?,
            Ended::Interrupt => write!(f, "; ended by an interrupt")?,
        }
        if !self.notes.is_empty() {
            write!(f, "; {}", self.notes.join("; "))?;
        }
        Ok(())
    }
}

/// A scene loaded into a `World` with the render schedules added.
pub struct Renderer {
    /// The world: scene entities, settings and render resources.
    pub world: World,
    prepared: bool,
    /// The film was made by `prepare` and holds no sample yet: the first pass loop
    /// writes its pages first (`Film::write_zeros`).
    film_fresh: bool,
    started: Option<Instant>,
    prepare_time: Duration,
    interrupt: Option<Arc<AtomicBool>>,
}

impl Renderer {
    /// Loads a scene file and applies `overrides`.
    pub fn from_file(path: &Path, overrides: &Overrides) -> Result<Self> {
        match SceneFormat::of(path) {
            SceneFormat::Ron => {
                let mut file = read_scene(path)?;
                overrides.apply(&mut file)?;
                Self::from_scene(&file, path)
            }
            SceneFormat::Gltf | SceneFormat::Obj => Self::from_model(path, overrides),
        }
    }

    /// Renders a model file (glTF, OBJ) directly, with an automatic camera and light
    /// where the file has none (see [`spawn_model`]).
    pub fn from_model(path: &Path, overrides: &Overrides) -> Result<Self> {
        let mut world = World::new();
        spawn_model(&mut world, path, overrides)?;
        Ok(Self::from_world(world))
    }

    /// A model file (glTF, OBJ) as a scene of one mesh entity with the camera and the
    /// default light that [`Renderer::from_model`] chooses written out, for drivers that
    /// work on a [`SceneFile`] (the debug, the viewer); also that renderer, unprepared,
    /// whose notes say what was chosen.
    pub fn model_scene(path: &Path, overrides: &Overrides) -> Result<(SceneFile, Self)> {
        let mut renderer = Self::from_model(path, overrides)?;
        let camera = renderer.camera().ok_or(GlintError::NoCamera)?;
        let absolute = std::fs::canonicalize(path)
            .unwrap_or_else(|_| path.to_owned())
            .to_string_lossy()
            .into_owned();
        let geometry = match SceneFormat::of(path) {
            SceneFormat::Obj => GeometryDesc::Obj { path: absolute },
            _ => GeometryDesc::Gltf {
                path: absolute,
                scene: None,
            },
        };
        let mut entities = vec![EntityDesc::Mesh(MeshDesc {
            name: None,
            geometry,
            material: None,
            transform: TransformDesc::default(),
        })];
        let mut lights = renderer.world.query::<(&Name, &PointLight)>();
        for (name, light) in lights.iter(&renderer.world) {
            if name.as_str() == DEFAULT_LIGHT_NAME {
                entities.push(EntityDesc::PointLight(PointLightDesc {
                    name: Some(DEFAULT_LIGHT_NAME.into()),
                    position: light.position,
                    color: light.color,
                }));
            }
        }
        let file = SceneFile {
            camera: CameraDesc::from(&camera),
            settings: renderer.settings().clone(),
            materials: Default::default(),
            entities,
        };
        Ok((file, renderer))
    }

    /// Builds the world from a parsed scene; `path` resolves relative paths.
    pub fn from_scene(file: &SceneFile, path: &Path) -> Result<Self> {
        let mut world = World::new();
        spawn_scene(&mut world, file, path)?;
        Ok(Self::from_world(world))
    }

    /// Wraps a world that already holds a scene (entities and [`Settings`]).
    pub fn from_world(mut world: World) -> Self {
        add_render_schedules(&mut world);
        world.init_resource::<Settings>();
        Self {
            world,
            prepared: false,
            film_fresh: false,
            started: None,
            prepare_time: Duration::ZERO,
            interrupt: None,
        }
    }

    /// The camera (the first one spawned).
    pub fn camera(&mut self) -> Option<Camera> {
        let mut q = self.world.query::<&Camera>();
        q.iter(&self.world).next().cloned()
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        self.world.resource::<Settings>()
    }

    /// Warnings the loader repaired.
    pub fn warnings(&self) -> Vec<String> {
        self.world
            .get_resource::<SceneSource>()
            .map(|s| s.warnings.clone())
            .unwrap_or_default()
    }

    /// Samples per pixel a full render takes.
    pub fn samples_per_pixel(&self) -> u32 {
        samples_per_pixel(self.settings())
    }

    /// Runs the [`crate::schedule::Prepare`] schedule once (analysis, tables, BVHs).
    pub fn prepare(&mut self) -> Result<()> {
        if self.prepared {
            return Ok(());
        }
        let start = *self.started.get_or_insert_with(Instant::now);
        let camera = self.camera().ok_or(GlintError::NoCamera)?;
        self.ensure_memory(&camera)?;
        let film = Film::try_new(camera.width, camera.height)?;
        self.world.insert_resource(film);
        self.film_fresh = true;
        self.prepared = true;
        let result = run_prepare(&mut self.world);
        self.prepare_time = start.elapsed();
        result
    }

    /// Refuses a render whose film and prepared geometry would not fit in memory.
    fn ensure_memory(&mut self, camera: &Camera) -> Result<()> {
        let mut meshes = self.world.query::<&Mesh>();
        // A mesh shared by several entities is prepared once, plus an instance per use.
        let mut uses: std::collections::HashMap<*const MeshData, (u64, u64)> = Default::default();
        for m in meshes.iter(&self.world) {
            let triangles = m.data.triangles.len() as u64;
            uses.entry(Arc::as_ptr(&m.data)).or_insert((0, triangles)).0 += 1;
        }
        let triangles: u64 = uses.values().map(|&(_, t)| t).sum();
        let instances: u64 = uses.values().map(|&(n, _)| n).filter(|&n| n >= 2).sum();
        let (w, h) = (camera.width as u64, camera.height as u64);
        let mut parts = vec![
            (
                format!("a {w}x{h} film"),
                memory::product(&[w, h, Film::BYTES_PER_PIXEL]),
            ),
            (
                format!("{triangles} triangles"),
                memory::product(&[triangles, memory::BYTES_PER_PREPARED_TRIANGLE]),
            ),
        ];
        if instances > 0 {
            parts.push((
                format!("{instances} instances"),
                memory::product(&[instances, memory::BYTES_PER_INSTANCE]),
            ));
        }
        Ok(memory::ensure_fits(&parts)?)
    }

    /// Starts over with `camera` and `settings`, for drivers that render one pass at a
    /// time while the view changes (`glint view`): the next pass goes into a new film of
    /// the camera's size. When the settings differ, the tables, the BVHs, the plan and the
    /// statistics are dropped and the prepare stage runs again before the next pass,
    /// because each of them depends on the settings.
    pub fn restart(&mut self, camera: &Camera, settings: &Settings) {
        let mut q = self.world.query::<&mut Camera>();
        if let Some(mut c) = q.iter_mut(&mut self.world).next() {
            *c = camera.clone();
        }
        if self.settings() != settings {
            self.world.insert_resource(settings.clone());
            self.world.insert_resource(RenderPlan::default());
            self.world.insert_resource(RenderStats::default());
            self.world.insert_resource(Materials::default());
            self.world.insert_resource(Lights::default());
            self.world.insert_resource(SceneGeometry::default());
            self.prepared = false;
            self.started = None;
        }
        // From the memory of the film it replaces, most often: already the process's
        // own and zeroed by the allocator, so nothing to write first.
        self.world
            .insert_resource(Film::new(camera.width, camera.height));
        self.film_fresh = false;
    }

    /// Stops renders when `flag` is set (e.g. by Ctrl-C): checked before every
    /// region, so a region in flight finishes and the film stays consistent.
    pub fn set_interrupt(&mut self, flag: Arc<AtomicBool>) {
        self.interrupt = Some(flag);
    }

    /// Whether the interrupt flag is set.
    pub fn interrupted(&self) -> bool {
        self.interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// Every pixel, as row-major indices, for a render of the whole film about to trace
    /// them (a fresh film's pages written first: `write_fresh_film`).
    fn all_pixels(&mut self) -> std::ops::Range<u32> {
        let film = self.world.resource::<Film>();
        let pixels = 0..film.width * film.height;
        self.write_fresh_film(std::slice::from_ref(&pixels));
        pixels
    }

    /// Before the first samples of a film made by `prepare`: writes its pages over the
    /// pixels `ranges` the render will trace (`Film::write_zeros`). Once per film.
    fn write_fresh_film(&mut self, ranges: &[std::ops::Range<u32>]) {
        if std::mem::take(&mut self.film_fresh) {
            let ranges: Vec<_> = ranges
                .iter()
                .map(|r| r.start as usize..r.end as usize)
                .collect();
            self.world.resource_mut::<Film>().write_zeros(&ranges);
        }
    }

    /// Traces sample index `sample` for every pixel, region by region; `progress`
    /// receives the pixels done after each region. An interrupt leaves the pass
    /// partial: the first regions hold one sample more than the others.
    pub fn render_pass(
        &mut self,
        sample: u32,
        progress: &mut (dyn FnMut(u64) + Send),
    ) -> Result<()> {
        self.prepare()?;
        let pixels = self.all_pixels();
        let mut control = Control {
            interrupt: self.interrupt.clone(),
            budget: None,
            start: Instant::now(),
            progress,
        };
        run_pass(&mut self.world, sample, pixels, &mut control).map(|_| ())
    }

    /// Renders every sample of every pixel; stops early after a pass if `budget` is
    /// spent, or between regions if the interrupt flag is set. Passes are sample
    /// indices in order, so a uniform-pattern run stopped after m passes (m >= 2)
    /// equals a run with `pixel_samples = m`; a stratified run stopped early has
    /// visited only the first m cells of its grid (see docs/convergence.md).
    pub fn render(
        &mut self,
        budget: Option<Duration>,
        progress: &mut (dyn FnMut(u64) + Send),
    ) -> Result<RenderSummary> {
        self.prepare()?;
        let start = self.started.unwrap_or_else(Instant::now);
        let n = self.samples_per_pixel();
        let pixels = self.all_pixels();
        let mut control = Control {
            interrupt: self.interrupt.clone(),
            budget,
            start,
            progress,
        };
        let done = run_passes(&mut self.world, 0..n, pixels, &mut control)?;
        let mut summary = self.summary(done, start.elapsed());
        summary.interrupted = done < n && self.interrupted();
        summary.ended = if summary.interrupted {
            Ended::Interrupt
        } else if done < n {
            Ended::Time
        } else {
            Ended::AllSamples
        };
        Ok(summary)
    }

    /// Renders until `rule` says stop. Without a target this is [`Renderer::render`];
    /// with one, passes go on past `pixel_samples` and the estimate is checked after
    /// every pass that completes a unit of the pattern (a stratified grid, a pair of
    /// Sobol' replicas) from [`MIN_TARGET_SPP`] on.
    pub fn render_until(
        &mut self,
        rule: &StopRule,
        progress: &mut (dyn FnMut(u64) + Send),
    ) -> Result<RenderSummary> {
        if rule.target_rmse.is_none() && rule.target_rel_error.is_none() {
            return self.render(rule.time, progress);
        }
        self.prepare()?;
        let start = self.started.unwrap_or_else(Instant::now);
        let settings = self.settings().clone();
        let method = EstimateMethod::for_settings(&settings);
        let step = check_every(&settings);
        let pixels = self.all_pixels();
        let mut control = Control {
            interrupt: self.interrupt.clone(),
            budget: None,
            start,
            progress,
        };
        let mut done = 0u32;
        // On one rayon worker, as in `run_passes`: one hand-off per render, not per region.
        let ended = rayon::scope(|_| -> Result<Ended> {
            loop {
                if !run_pass(&mut self.world, done, pixels.clone(), &mut control)? {
                    return Ok(Ended::Interrupt);
                }
                done += 1;
                if done.is_multiple_of(step)
                    && done >= MIN_TARGET_SPP
                    && rule.reached(self.film().error_estimate(method).as_ref())
                {
                    return Ok(Ended::Target);
                }
                if rule.time.is_some_and(|t| start.elapsed() >= t) {
                    return Ok(Ended::Time);
                }
                if done == u32::MAX {
                    return Ok(Ended::AllSamples);
                }
            }
        })?;
        let mut summary = self.summary(done, start.elapsed());
        summary.interrupted = ended == Ended::Interrupt;
        summary.ended = ended;
        Ok(summary)
    }

    /// The film's estimate of its error, by the method its settings call for.
    pub fn error_estimate(&self) -> Option<ErrorEstimate> {
        self.film()
            .error_estimate(EstimateMethod::for_settings(self.settings()))
    }

    /// Renders sample indices `samples` over the window `crop` only (a part of a split
    /// render, see [`crate::film::part`]): the pixels outside stay empty. Stops between
    /// regions if the interrupt flag is set (`interrupted` in the summary).
    pub fn render_part(
        &mut self,
        samples: std::ops::Range<u32>,
        crop: Crop,
        progress: &mut (dyn FnMut(u64) + Send),
    ) -> Result<RenderSummary> {
        self.prepare()?;
        let start = self.started.unwrap_or_else(Instant::now);
        let (width, height) = (self.film().width, self.film().height);
        crop.check(width, height).map_err(GlintError::Setting)?;
        let n = self.samples_per_pixel();
        if samples.start >= samples.end || samples.end > n {
            return Err(GlintError::Setting(format!(
                "the sample range {}..{} is not a non-empty part of the render's 0..{n}",
                samples.start, samples.end
            )));
        }
        let mut control = Control {
            interrupt: self.interrupt.clone(),
            budget: None,
            start,
            progress,
        };
        let rows = crop.pixel_ranges(width);
        self.write_fresh_film(&rows);
        let mut done = 0;
        // On one rayon worker, as in `run_passes`: one hand-off per render, not per region.
        rayon::scope(|_| -> Result<()> {
            'passes: for sample in samples.clone() {
                for pixels in &rows {
                    if !run_pass(&mut self.world, sample, pixels.clone(), &mut control)? {
                        break 'passes;
                    }
                }
                done += 1;
            }
            Ok(())
        })?;
        let mut summary = self.summary(done, start.elapsed());
        summary.width = crop.width();
        summary.height = crop.height();
        summary.interrupted = done < samples.len() as u32;
        Ok(summary)
    }

    /// The settings and camera as one line of text: parts of a split render must agree
    /// on it.
    pub fn settings_text(&mut self) -> String {
        let settings = ron::to_string(self.settings()).unwrap_or_default();
        format!("{settings} camera {:?}", self.camera())
    }

    /// The part of the film that [`Renderer::render_part`] rendered, for `glint merge`.
    pub fn part(&mut self, scene_hash: String, samples: std::ops::Range<u32>, crop: Crop) -> Part {
        let film = self.film();
        let (width, height) = (film.width, film.height);
        let film = crop_film(film, crop);
        Part {
            info: PartInfo {
                scene_hash,
                settings: self.settings_text(),
                width,
                height,
                samples,
                crop,
            },
            film,
        }
    }

    /// A summary of the run so far.
    pub fn summary(&self, samples: u32, elapsed: Duration) -> RenderSummary {
        let film = self.world.resource::<Film>();
        RenderSummary {
            width: film.width,
            height: film.height,
            samples,
            seconds: elapsed.as_secs_f64(),
            prepare_seconds: self.prepare_time.as_secs_f64(),
            stats: self.world.resource::<RenderStats>().clone(),
            notes: self
                .world
                .get_resource::<SceneSource>()
                .map(|s| s.notes.clone())
                .unwrap_or_default(),
            interrupted: false,
            error: self.error_estimate(),
            ended: Ended::AllSamples,
        }
    }

    /// The film.
    pub fn film(&self) -> &Film {
        self.world.resource::<Film>()
    }

    /// Statistics of the run so far.
    pub fn stats(&self) -> &RenderStats {
        self.world.resource::<RenderStats>()
    }

    /// The plan (valid after [`Renderer::prepare`]).
    pub fn plan(&self) -> &RenderPlan {
        self.world.resource::<RenderPlan>()
    }
}

/// Passes between checks of an error target: a whole stratified grid, or both Sobol'
/// replicas, so the estimate is judged on complete patterns.
fn check_every(settings: &Settings) -> u32 {
    match (settings.sampler, pixel_mode(settings)) {
        (SamplerKind::Sobol, _) => 2,
        (_, PixelSampling::Stratified) => samples_per_pixel(settings).max(1),
        _ => 1,
    }
}

/// The render driver's answers to the pass loop: an interrupt flag, a time budget, a
/// progress callback.
struct Control<'a> {
    interrupt: Option<Arc<AtomicBool>>,
    budget: Option<Duration>,
    start: Instant,
    progress: &'a mut (dyn FnMut(u64) + Send),
}

impl PassControl for Control<'_> {
    fn proceed(&mut self) -> bool {
        !self
            .interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    }

    fn region_done(&mut self, pixels: u64) {
        (self.progress)(pixels);
    }

    fn another_pass(&mut self) -> bool {
        self.budget.is_none_or(|b| self.start.elapsed() < b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mrays_per_second_leaves_out_the_prepare_stage() {
        let mut stats = RenderStats::default();
        stats.rays.camera = 3_000_000;
        let summary = RenderSummary {
            width: 1,
            height: 1,
            samples: 1,
            seconds: 4.0,
            prepare_seconds: 1.0,
            stats,
            notes: Vec::new(),
            interrupted: false,
            error: None,
            ended: Ended::AllSamples,
        };
        assert_eq!(summary.trace_seconds(), 3.0);
        assert_eq!(summary.mrays_per_second(), 1.0);
        let text = summary.to_string();
        assert!(
            text.contains("4.00 s (1.00 s prepare, 3.00 s trace)") && text.contains("1.00 Mrays/s"),
            "{text}"
        );
    }
}
