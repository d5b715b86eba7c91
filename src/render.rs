//! The render driver: loads a scene into a `World`, runs the schedules, reports.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;

use crate::error::{GlintError, Result};
use crate::film::Film;
use crate::sampling::samples_taken;
use crate::scene::format::SceneFile;
use crate::scene::model::{SceneFormat, spawn_model};
use crate::scene::{Camera, SceneSource, Settings, read_scene, spawn_scene};
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
}

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
        let s = self.settings();
        samples_taken(s.pixel_samples, s.pixel_sampling)
    }

    /// Runs the [`crate::schedule::Prepare`] schedule once (analysis, tables, BVHs).
    pub fn prepare(&mut self) -> Result<()> {
        if self.prepared {
            return Ok(());
        }
        let start = *self.started.get_or_insert_with(Instant::now);
        let camera = self.camera().ok_or(GlintError::NoCamera)?;
        self.world
            .insert_resource(Film::new(camera.width, camera.height));
        self.prepared = true;
        let result = run_prepare(&mut self.world);
        self.prepare_time = start.elapsed();
        result
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
        self.world
            .insert_resource(Film::new(camera.width, camera.height));
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

    /// Every pixel, as row-major indices.
    fn all_pixels(&self) -> std::ops::Range<u32> {
        let film = self.world.resource::<Film>();
        0..film.width * film.height
    }

    /// Traces sample index `sample` for every pixel, region by region; `progress`
    /// receives the pixels done after each region. An interrupt leaves the pass
    /// partial: the first regions hold one sample more than the others.
    pub fn render_pass(&mut self, sample: u32, progress: &mut dyn FnMut(u64)) -> Result<()> {
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
        progress: &mut dyn FnMut(u64),
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
        Ok(summary)
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

/// The render driver's answers to the pass loop: an interrupt flag, a time budget, a
/// progress callback.
struct Control<'a> {
    interrupt: Option<Arc<AtomicBool>>,
    budget: Option<Duration>,
    start: Instant,
    progress: &'a mut dyn FnMut(u64),
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
