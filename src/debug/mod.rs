//! The visual debug: explains one pixel with debug-primitive entities.
//!
//! A debug run is a render of one pixel by the render's own schedules
//! ([`crate::schedule`]), one pixel per sample index. It adds a trace log
//! ([`TraceLog`](crate::trace::log::TraceLog)), which the hot loops fill inline, and the
//! [`record`] systems, which copy what each stage did into the [`DebugTrace`]. The
//! [`DebugEmit`] schedule's emitter systems, one per [`Feature`], then turn that trace into
//! [`DebugPrimitive`] entities, which [`overlay`] draws over a view of the scene from
//! another viewpoint and [`dump`] writes as RON.
//!
//! ```text
//! RenderPass:  generate_camera_samples -> record_camera_samples -> trace_wavefronts ...
//! Bounce:      intersect_rays -> record_rays -> shade_hits -> record_light_samples
//!              -> trace_shadow_rays? -> record_shadow_results -> gather_radiance
//!              -> record_radiance -> spawn ...
//! DebugEmit (once, after the pixel's samples):
//!     emit_pixel, emit_reflections?, emit_transparency?, emit_bvh?, emit_bvh_level?,
//!     emit_textures?, emit_lights?, emit_samples?
//! ```
//! A `?` emitter runs only when its feature is on in the scene and asked for.

pub mod dump;
pub mod emit;
pub mod log;
pub mod overlay;
pub mod primitives;
pub mod record;
pub mod view;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use glam::Vec3;
use rayon::prelude::*;

use crate::accel::Aabb;
use crate::error::{GlintError, Result};
use crate::film::{Encoding, write_image};
use crate::render::{Overrides, Renderer};
use crate::scene::format::SceneFile;
use crate::scene::model::SceneFormat;
use crate::scene::{Acceleration, Settings, read_scene};
use crate::schedule::run_passes;
use crate::trace::geometry::SceneGeometry;
use crate::trace::lights::Lights;
use crate::trace::materials::Materials;
use crate::trace::plan::{BinaryBvhObserver, RenderPlan};
use crate::trace::surface::surface_at;

pub use log::DebugTrace;
pub use overlay::Canvas;
pub use primitives::{DebugOrder, DebugPrimitive, Feature, Shape, Values};
pub use view::ViewCamera;

/// Brightness of the flat-shaded preview under the background render.
const PREVIEW_FLOOR: f32 = 0.35;

/// Runs the emitters once after a debug trace.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct DebugEmit;

/// What a debug run explains: the pixel and the features asked for.
#[derive(Resource, Clone, Debug, PartialEq, Eq)]
pub struct DebugRequest {
    /// Pixel `[x, y]` (row 0 at the top).
    pub pixel: [u32; 2],
    /// Features asked for (the pixel itself is always shown).
    pub features: BTreeSet<Feature>,
    /// Show every BVH node at this level for the whole scene.
    pub bvh_level: Option<u32>,
}

impl DebugRequest {
    /// Every feature, for pixel `(x, y)`.
    pub fn all(x: u32, y: u32) -> Self {
        Self {
            pixel: [x, y],
            features: Feature::ALL.into_iter().collect(),
            bvh_level: None,
        }
    }
}

/// Whether `feature` is on in this scene with these settings (decided by the render plan).
pub fn feature_in_scene(
    feature: Feature,
    plan: &RenderPlan,
    settings: &Settings,
    lights: &Lights,
) -> bool {
    match feature {
        Feature::Pixel => true,
        Feature::Reflections => plan.reflections,
        Feature::Transparency => plan.pass_through,
        Feature::Bvh => {
            settings.acceleration == Acceleration::Bvh && (plan.triangle_bvh || plan.sphere_bvh)
        }
        Feature::Textures => plan.textures,
        Feature::Lights => !lights.is_empty(),
        Feature::Samples => plan.pixel_patterns,
    }
}

/// The resources a feature's run condition reads.
type FeatureInputs<'w> = (
    Option<Res<'w, DebugRequest>>,
    Res<'w, RenderPlan>,
    Res<'w, Settings>,
    Res<'w, Lights>,
);

/// Run condition: a debug run that asked for `feature`, in a scene where it is on.
fn wanted(feature: Feature) -> impl FnMut(FeatureInputs) -> bool + Clone {
    move |(request, plan, settings, lights): FeatureInputs| {
        request.is_some_and(|r| feature == Feature::Pixel || r.features.contains(&feature))
            && feature_in_scene(feature, &plan, &settings, &lights)
    }
}

/// The [`DebugEmit`] schedule: every emitter, each behind its feature's run condition,
/// all behind the presence of a [`DebugTrace`].
pub fn debug_emit_schedule() -> Schedule {
    use emit::*;
    let mut s = Schedule::new(DebugEmit);
    s.add_systems(
        (
            emit_pixel.run_if(wanted(Feature::Pixel)),
            emit_reflections.run_if(wanted(Feature::Reflections)),
            emit_transparency.run_if(wanted(Feature::Transparency)),
            emit_bvh.run_if(wanted(Feature::Bvh)),
            emit_bvh_level
                .run_if(wanted(Feature::Bvh))
                .run_if(|r: Option<Res<DebugRequest>>| r.is_some_and(|r| r.bvh_level.is_some())),
            emit_textures.run_if(wanted(Feature::Textures)),
            emit_lights.run_if(wanted(Feature::Lights)),
            emit_samples.run_if(wanted(Feature::Samples)),
        )
            // Because the dump and the legend list primitives in spawn order.
            .chain()
            .run_if(resource_exists::<DebugTrace>),
    );
    s
}

/// A traced pixel: the render's world holding the trace log and the debug entities.
pub struct DebugSession {
    /// The renderer whose schedules traced the pixel.
    pub renderer: Renderer,
    /// The scene, for the background render from the view.
    scene: SceneFile,
    /// Where the scene came from (resolves relative paths).
    path: PathBuf,
}

impl DebugSession {
    /// Traces pixel `request.pixel` of `scene` with the render's schedules, then emits the
    /// debug entities.
    pub fn trace(scene: &SceneFile, path: &Path, request: DebugRequest) -> Result<Self> {
        let mut renderer = Renderer::from_scene(scene, path)?;
        let camera = renderer.camera().ok_or(GlintError::NoCamera)?;
        let [x, y] = request.pixel;
        if x >= camera.width || y >= camera.height {
            return Err(GlintError::PixelOutside {
                pixel: [x, y],
                size: [camera.width, camera.height],
            });
        }
        record::add_recorders(&mut renderer.world);
        renderer.world.init_resource::<emit::SpawnedPrimitives>();
        renderer.world.insert_resource(request);
        // The trace log and the BVH view name the binary tree's nodes.
        renderer
            .world
            .insert_resource(BinaryBvhObserver("the debug's trace log and BVH view"));
        renderer.world.add_schedule(debug_emit_schedule());
        renderer.prepare()?;
        let pixel = y * camera.width + x;
        let samples = 0..renderer.samples_per_pixel();
        run_passes(&mut renderer.world, samples, pixel..pixel + 1, &mut ())?;
        renderer.world.run_schedule(DebugEmit);
        Ok(Self {
            renderer,
            scene: scene.clone(),
            path: path.to_owned(),
        })
    }

    /// The pixel's colour as the debug trace computed it (the film's mean of its samples).
    pub fn pixel_color(&self) -> Vec3 {
        let [x, y] = self.request().pixel;
        self.renderer.film().pixel(x, y)
    }

    /// The request.
    pub fn request(&self) -> &DebugRequest {
        self.renderer.world.resource::<DebugRequest>()
    }

    /// The trace log.
    pub fn log(&self) -> &DebugTrace {
        self.renderer.world.resource::<DebugTrace>()
    }

    /// Every debug primitive, in spawn order.
    pub fn primitives(&mut self) -> Vec<DebugPrimitive> {
        let mut q = self
            .renderer
            .world
            .query::<(&DebugOrder, &DebugPrimitive)>();
        let mut v: Vec<(DebugOrder, DebugPrimitive)> = q
            .iter(&self.renderer.world)
            .map(|(n, p)| (*n, p.clone()))
            .collect();
        v.sort_by_key(|(n, _)| *n);
        v.into_iter().map(|(_, p)| p).collect()
    }

    /// Which of the asked features are off in this scene, for a note to the user.
    pub fn features_off(&self) -> Vec<Feature> {
        let w = &self.renderer.world;
        let (plan, settings, lights) = (
            w.resource::<RenderPlan>(),
            w.resource::<Settings>(),
            w.resource::<Lights>(),
        );
        self.request()
            .features
            .iter()
            .copied()
            .filter(|f| !feature_in_scene(*f, plan, settings, lights))
            .collect()
    }

    /// Bounds of the scene and of every point of the traced path (the camera origin excepted).
    pub fn framed_bounds(&self) -> Aabb {
        let mut b = self.renderer.world.resource::<SceneGeometry>().bounds();
        for r in &self.log().rays {
            if r.depth > 0 {
                b.grow(r.ray.origin);
            }
            if let Some((_, s)) = &r.hit {
                b.grow(s.p);
            }
        }
        for l in &self.log().lights {
            b.grow(l.light.position);
        }
        if b.is_empty() {
            let c = self
                .renderer
                .world
                .resource::<DebugTrace>()
                .camera_samples
                .first();
            let o = c.map_or(Vec3::ZERO, |c| c.ray.at(1.0));
            b = Aabb::new(o - Vec3::ONE, o + Vec3::ONE);
        }
        b
    }

    /// The view camera: from `view_from` if given, else an automatic oblique viewpoint.
    pub fn view(&mut self, view_from: Option<Vec3>, width: u32, height: u32) -> ViewCamera {
        let render = self.renderer.camera().expect("checked in trace");
        let bounds = self.framed_bounds();
        match view_from {
            Some(p) => view::view_from(&render, p, bounds, width, height),
            None => {
                let path: Vec<Vec3> = self
                    .log()
                    .rays
                    .iter()
                    .filter_map(|r| r.hit.as_ref().map(|(_, s)| s.p - r.ray.origin))
                    .collect();
                view::auto_view(&render, bounds, &path, width, height)
            }
        }
    }

    /// A fast render of the scene from `view` (1 sample per pixel, at most 4 shadow samples).
    pub fn background(&self, view: &ViewCamera) -> Result<Canvas> {
        let mut file = self.scene.clone();
        let c = &view.camera;
        file.camera.position = c.position;
        file.camera.look_at = c.look_at;
        file.camera.up = c.up;
        file.camera.fov_y = c.fov_y_degrees;
        file.camera.width = c.width;
        file.camera.height = c.height;
        file.settings.pixel_samples = 1;
        file.settings.shadow_samples = file.settings.shadow_samples.min(4);
        let mut r = Renderer::from_scene(&file, &self.path)?;
        r.render(None, &mut |_| {})?;
        let film = r.film();
        Ok(Canvas {
            width: film.width,
            height: film.height,
            pixels: film.image(),
        })
    }

    /// View-space depth of the scene at each pixel of `view` (infinite on a miss), and a
    /// flat-shaded preview (`kd` by the cosine to the viewer).
    pub fn scene_view(&self, view: &ViewCamera) -> (Vec<f32>, Vec<Vec3>) {
        let w = &self.renderer.world;
        let (g, materials) = (w.resource::<SceneGeometry>(), w.resource::<Materials>());
        let (width, height) = (view.camera.width, view.camera.height);
        (0..width * height)
            .into_par_iter()
            .map(|i| {
                let ray = view
                    .basis
                    .ray((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
                match g.intersect(&ray, f32::INFINITY, &mut ()) {
                    Some(hit) => {
                        let s = surface_at(g, &ray, &hit, true);
                        let kd = materials.kd_at(s.material, s.uv);
                        let cos = s.n.dot(-ray.dir).abs();
                        (view.depth(s.p), kd * (0.3 + 0.7 * cos))
                    }
                    None => (f32::INFINITY, Vec3::ZERO),
                }
            })
            .unzip()
    }

    /// Draws the debug primitives over `background` as seen from `view`. Where the
    /// background is darker than a dim flat-shaded preview (unlit backs of walls, shadows),
    /// the preview shows through, so the scene's shape stays readable.
    pub fn draw(&mut self, view: &ViewCamera, background: Canvas, depth_test: bool) -> Canvas {
        let (depth, flat) = self.scene_view(view);
        let depth = depth_test.then_some(depth);
        let prims = self.primitives();
        let refs: Vec<&DebugPrimitive> = prims.iter().collect();
        let textures = self.renderer.world.resource::<Materials>().textures.clone();
        let mut canvas = background;
        if canvas.pixels.len() == flat.len() {
            for (p, f) in canvas.pixels.iter_mut().zip(&flat) {
                *p = p.max(*f * PREVIEW_FLOOR);
            }
        }
        overlay::draw_primitives(
            &mut canvas,
            &overlay::OverlayInput {
                view,
                scene_depth: depth.as_deref(),
                textures: &textures,
            },
            &refs,
        );
        canvas
    }

    /// The debug entities as RON text.
    pub fn dump_ron(&mut self) -> Result<String> {
        let prims = self.primitives();
        dump::to_ron(self.request(), self.pixel_color(), &prims)
    }
}

/// What `glint debug` produces beyond tracing the pixel.
#[derive(Clone, Debug)]
pub struct DebugOptions {
    /// The pixel to explain, `[x, y]` (row 0 at the top).
    pub pixel: [u32; 2],
    /// Output image (PNG).
    pub output: PathBuf,
    /// Features to explain (`None`: all that are on in the scene).
    pub features: Option<Vec<Feature>>,
    /// View the scene from this point (`None`: an automatic oblique viewpoint).
    pub view_from: Option<Vec3>,
    /// Size of the debug image, `[width, height]`.
    pub view_size: [u32; 2],
    /// Fade the parts of primitives that the scene hides from the view.
    pub depth_test: bool,
    /// Also show every BVH node at this level, for the whole scene.
    pub bvh_level: Option<u32>,
    /// Also write the debug entities as RON to this file.
    pub dump: Option<PathBuf>,
}

/// What a debug run wrote and found.
#[derive(Clone, Debug)]
pub struct DebugOutcome {
    /// Notes for the user (features asked for that are off in this scene).
    pub notes: Vec<String>,
    /// The pixel's colour (the film's mean of its samples).
    pub pixel_color: Vec3,
    /// How many debug entities the run spawned.
    pub entities: usize,
}

/// Traces one pixel, writes the debug image and optionally the dump.
pub fn run(scene: &Path, overrides: &Overrides, options: &DebugOptions) -> Result<DebugOutcome> {
    let ext = options.output.extension().and_then(|e| e.to_str());
    if !ext.is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        return Err(GlintError::Output {
            path: options.output.clone(),
            message: "the debug image must be a .png".into(),
        });
    }
    let file = match SceneFormat::of(scene) {
        SceneFormat::Ron => {
            let mut file = read_scene(scene)?;
            overrides.apply(&mut file)?;
            file
        }
        SceneFormat::Gltf | SceneFormat::Obj => Renderer::model_scene(scene, overrides)?.0,
    };
    let request = DebugRequest {
        pixel: options.pixel,
        features: match &options.features {
            Some(f) => f.iter().copied().collect(),
            None => Feature::ALL.into_iter().collect(),
        },
        bvh_level: options.bvh_level,
    };
    let mut session = DebugSession::trace(&file, scene, request)?;
    let mut notes = Vec::new();
    if options.features.is_some() {
        for f in session.features_off() {
            notes.push(format!(
                "{} is off in this scene; nothing to show for it",
                f.name()
            ));
        }
    }
    let [w, h] = options.view_size;
    let view = session.view(options.view_from, w, h);
    let background = session.background(&view)?;
    let canvas = session.draw(&view, background, options.depth_test);
    write_image(&options.output, w, h, &canvas.pixels, Encoding::Linear)?;
    if let Some(path) = &options.dump {
        let text = session.dump_ron()?;
        crate::film::write_atomically(path, text.as_bytes())?;
    }
    Ok(DebugOutcome {
        notes,
        pixel_color: session.pixel_color(),
        entities: session.primitives().len(),
    })
}
