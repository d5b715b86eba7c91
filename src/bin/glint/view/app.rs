//! The viewer's window: the image, the camera controls, the panels, the status line.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use egui::{Color32, Key, PointerButton, Rect, Sense, TextureHandle, TextureOptions};
use glint::Renderer;
use glint::debug::Feature;
use glint::film::{Encoding, to_rgb8, write_atomically, write_image};
use glint::scene::{Camera, Settings};

use super::controls;
use super::scene::ViewScene;
use super::traces::{Projector, TracedPixel, draw_traces, trace_pixel};
use super::worker::{Frame, Job, Report, Wake, Worker};

/// Width of the side panel, in points, when the window opens.
pub const PANEL_WIDTH: f32 = 320.0;
/// The camera counts as moving for this long after the last input that moved it.
const SETTLE: Duration = Duration::from_millis(150);
/// Flight speed: the distance to the point looked at, per second.
const FLY_SPEED: f32 = 0.6;

/// The viewer's state: the scene, the view, the render thread, the traced pixels.
pub struct Viewer {
    /// The scene as loaded.
    pub scene: ViewScene,
    /// The current camera; its size follows the image area of the window.
    pub camera: Camera,
    /// The current settings.
    pub settings: Settings,
    /// Numbers the jobs: increases with every change of view or settings.
    pub generation: u64,
    /// The newest frame received.
    pub frame: Option<Frame>,
    /// The newest complete full-resolution frame of the current job, for saving.
    pub finished: Option<Frame>,
    /// The image's place on screen, in points.
    pub image_rect: Rect,
    /// Kept traced pixels, oldest first.
    pub traces: Vec<TracedPixel>,
    /// Debug features drawn.
    pub shown: BTreeSet<Feature>,
    /// BVH level to show for the whole scene in the next traces.
    pub bvh_level: Option<u32>,
    /// Where "save image" writes (.png or .exr).
    pub image_path: String,
    /// Where "save scene" writes.
    pub scene_path: String,
    /// The last message for the status line (saved files, errors).
    pub message: String,
    /// Time to the first frame, in milliseconds.
    pub first_frame_ms: Option<f64>,
    pub(super) gradient_text: [String; 2],
    worker: Worker,
    wake: Wake,
    submitted: Option<Job>,
    last_motion: Option<Instant>,
    texture: Option<TextureHandle>,
    /// A frame arrived that the texture does not show yet.
    fresh: bool,
    pending: Vec<Receiver<glint::Result<TracedPixel>>>,
    opened: Instant,
}

impl Viewer {
    /// A viewer of `scene`; the render thread starts at once and renders when the
    /// window first shows its size.
    pub fn new(scene: ViewScene) -> glint::Result<Self> {
        let renderer = Renderer::from_scene(&scene.file, &scene.path)?;
        let wake: Wake = Arc::new(Mutex::new(None));
        let worker = Worker::spawn(renderer, wake.clone());
        let stem = scene
            .path
            .file_stem()
            .map_or("view".into(), |s| s.to_string_lossy().into_owned());
        let settings = scene.file.settings.clone();
        Ok(Self {
            camera: scene.camera(),
            gradient_text: [
                ron::to_string(&settings.gradient).unwrap_or_default(),
                ron::to_string(&settings.comparison_gradient).unwrap_or_default(),
            ],
            settings,
            generation: 0,
            frame: None,
            finished: None,
            image_rect: Rect::NOTHING,
            traces: Vec::new(),
            shown: Feature::ALL.into_iter().collect(),
            bvh_level: None,
            image_path: format!("{stem}_view.png"),
            scene_path: format!("{stem}_view.ron"),
            message: scene.notes.join("; "),
            first_frame_ms: None,
            worker,
            wake,
            submitted: None,
            last_motion: None,
            texture: None,
            fresh: false,
            pending: Vec::new(),
            opened: Instant::now(),
            scene,
        })
    }

    /// Draws the whole window and handles its input.
    pub fn show(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        {
            let mut wake = self.wake.lock().expect("wake lock");
            if wake.is_none() {
                let c = ctx.clone();
                *wake = Some(Box::new(move || c.request_repaint()));
            }
        }
        self.receive(&ctx);
        egui::Panel::bottom("status").show(ui, |ui| self.status_line(ui));
        egui::Panel::left("panel")
            .resizable(true)
            .default_size(PANEL_WIDTH)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
            });
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE.fill(Color32::BLACK))
            .show(ui, |ui| self.image_area(ui));
        self.submit(&ctx);
    }

    /// Takes the render thread's reports and the finished traces.
    fn receive(&mut self, ctx: &egui::Context) {
        while let Ok(report) = self.worker.reports.try_recv() {
            self.take(report);
        }
        self.pending.retain(|rx| match rx.try_recv() {
            Ok(result) => {
                match result {
                    Ok(t) => self.traces.push(t),
                    Err(e) => self.message = format!("trace: {e}"),
                }
                false
            }
            Err(std::sync::mpsc::TryRecvError::Empty) => true,
            Err(_) => false,
        });
        if !self.pending.is_empty() {
            ctx.request_repaint_after(Duration::from_millis(30));
        }
        if let Some(f) = &self.frame
            && std::mem::take(&mut self.fresh)
        {
            let image = egui::ColorImage::from_rgb(
                [f.width as usize, f.height as usize],
                &to_rgb8(&f.pixels, Encoding::Linear),
            );
            let options = if f.coarse {
                TextureOptions::NEAREST
            } else {
                TextureOptions::LINEAR
            };
            match &mut self.texture {
                Some(t) => t.set(image, options),
                None => self.texture = Some(ctx.load_texture("render", image, options)),
            }
        }
    }

    fn take(&mut self, report: Report) {
        match report {
            Report::Frame(f) => {
                if self.first_frame_ms.is_none() {
                    self.first_frame_ms = Some(self.opened.elapsed().as_secs_f64() * 1e3);
                }
                if f.generation == self.generation && f.done && !f.coarse {
                    self.finished = Some((*f).clone());
                }
                self.frame = Some(*f);
                self.fresh = true;
            }
            Report::Error(generation, e) => {
                if generation == self.generation {
                    self.message = format!("render: {e}");
                }
            }
        }
    }

    /// Sends the render thread the current view when it changed.
    fn submit(&mut self, ctx: &egui::Context) {
        let moving = self.last_motion.is_some_and(|t| t.elapsed() < SETTLE);
        if moving {
            ctx.request_repaint_after(SETTLE);
        }
        if self.camera.width == 0 || self.camera.height == 0 {
            return;
        }
        let same = self.submitted.as_ref().is_some_and(|j| {
            j.camera == self.camera && j.settings == self.settings && j.moving == moving
        });
        if same {
            return;
        }
        self.generation += 1;
        self.finished = None;
        let job = Job {
            generation: self.generation,
            camera: self.camera.clone(),
            settings: self.settings.clone(),
            moving,
        };
        self.worker.submit(job.clone());
        self.submitted = Some(job);
    }

    /// The image, with the traced pixels' primitives over it, and the mouse and keys.
    fn image_area(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        self.image_rect = rect;
        let ppp = ui.ctx().pixels_per_point();
        let (w, h) = (
            (rect.width() * ppp).round().max(1.0) as u32,
            (rect.height() * ppp).round().max(1.0) as u32,
        );
        self.camera.width = w;
        self.camera.height = h;
        let painter = ui.painter_at(rect);
        if let Some(t) = &self.texture {
            let uv = Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            painter.image(t.id(), rect, uv, Color32::WHITE);
        }
        draw_traces(
            &painter,
            &Projector::new(&self.camera, rect),
            &mut self.traces,
            &self.shown,
        );

        let mut moved = false;
        let shift = ui.input(|i| i.modifiers.shift);
        let keys_free = !ui.ctx().egui_wants_keyboard_input();
        if response.dragged_by(PointerButton::Primary) && !shift {
            let d = response.drag_delta();
            controls::orbit(&mut self.camera, d.x, d.y);
            moved |= d != egui::Vec2::ZERO;
        }
        if response.dragged_by(PointerButton::Secondary)
            || response.dragged_by(PointerButton::Middle)
            || (response.dragged_by(PointerButton::Primary) && shift)
        {
            let d = response.drag_delta();
            controls::pan(&mut self.camera, d.x, d.y, rect.height());
            moved |= d != egui::Vec2::ZERO;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                controls::zoom(&mut self.camera, scroll / 50.0);
                moved = true;
            }
        }
        if keys_free {
            let dt = ui.input(|i| i.stable_dt).min(0.1);
            let axis = |plus: Key, minus: Key| {
                ui.input(|i| i.key_down(plus) as i32 as f32 - i.key_down(minus) as i32 as f32)
            };
            let (f, r, u) = (
                axis(Key::W, Key::S),
                axis(Key::D, Key::A),
                axis(Key::E, Key::Q),
            );
            if (f, r, u) != (0.0, 0.0, 0.0) {
                let s = FLY_SPEED * dt;
                controls::fly(&mut self.camera, f * s, r * s, u * s);
                moved = true;
                ui.ctx().request_repaint();
            }
            if ui.input(|i| i.key_pressed(Key::Home)) {
                self.reset_camera();
            }
            if ui.input(|i| i.key_pressed(Key::C)) {
                self.traces.clear();
            }
            if ui.input(|i| i.key_pressed(Key::R))
                && let Some(p) = response.hover_pos()
            {
                self.trace_at(p);
            }
        }
        if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
        {
            self.trace_at(p);
        }
        if moved {
            self.last_motion = Some(Instant::now());
        }
    }

    /// The camera of the scene, at the window's size.
    pub fn reset_camera(&mut self) {
        let (w, h) = (self.camera.width, self.camera.height);
        self.camera = self.scene.camera();
        self.camera.width = w;
        self.camera.height = h;
    }

    /// The image pixel under screen point `p`, if `p` is on the image.
    pub fn pixel_at(&self, p: egui::Pos2) -> Option<[u32; 2]> {
        let r = self.image_rect;
        if !r.contains(p) {
            return None;
        }
        let x = ((p.x - r.min.x) / r.width() * self.camera.width as f32) as u32;
        let y = ((p.y - r.min.y) / r.height() * self.camera.height as f32) as u32;
        Some([x.min(self.camera.width - 1), y.min(self.camera.height - 1)])
    }

    /// Traces the pixel under `p` on a thread of its own (a large scene takes a while).
    pub fn trace_at(&mut self, p: egui::Pos2) {
        let Some(pixel) = self.pixel_at(p) else {
            return;
        };
        let (tx, rx) = channel();
        let (scene, camera, settings, level) = (
            self.scene.clone(),
            self.camera.clone(),
            self.settings.clone(),
            self.bvh_level,
        );
        let wake = self.wake.clone();
        std::thread::spawn(move || {
            let _ = tx.send(trace_pixel(&scene, &camera, &settings, pixel, level));
            if let Some(w) = wake.lock().expect("wake lock").as_ref() {
                w();
            }
        });
        self.pending.push(rx);
        self.message = format!("tracing pixel {},{}", pixel[0], pixel[1]);
    }

    /// Waits for the traces in flight.
    #[allow(
        dead_code,
        reason = "for tests/view.rs, which drives the window headless"
    )]
    pub fn wait_traces(&mut self) {
        for rx in std::mem::take(&mut self.pending) {
            match rx.recv() {
                Ok(Ok(t)) => self.traces.push(t),
                Ok(Err(e)) => self.message = format!("trace: {e}"),
                Err(_) => {}
            }
        }
    }

    /// Waits until the render thread has finished the current job; returns that frame.
    #[allow(
        dead_code,
        reason = "for tests/view.rs, which drives the window headless"
    )]
    pub fn wait_finished(&mut self) -> Option<&Frame> {
        while self.finished.is_none() {
            match self.worker.reports.recv_timeout(Duration::from_secs(120)) {
                Ok(Report::Error(g, e)) if g == self.generation => {
                    self.message = format!("render: {e}");
                    return None;
                }
                Ok(r) => self.take(r),
                Err(_) => return None,
            }
        }
        self.finished.as_ref()
    }

    /// Writes the newest finished image (PNG or EXR by extension).
    pub fn save_image(&mut self, path: &str) -> glint::Result<()> {
        let Some(f) = self.finished.as_ref().or(self.frame.as_ref()) else {
            return Ok(());
        };
        write_image(
            &PathBuf::from(path),
            f.width,
            f.height,
            &f.pixels,
            Encoding::Linear,
        )
    }

    /// Writes the scene with the current camera and settings as RON.
    pub fn save_scene(&self, path: &str) -> glint::Result<()> {
        let text = self.scene.to_ron(&self.camera, &self.settings);
        write_atomically(&PathBuf::from(path), text.as_bytes())
    }

    fn status_line(&self, ui: &mut egui::Ui) {
        let text = match &self.frame {
            None => "rendering…".to_owned(),
            Some(f) => {
                let spp = if f.coarse {
                    format!("coarse {}x{}", f.width, f.height)
                } else {
                    format!("{}/{} spp", f.samples, f.target)
                };
                let skipped = if f.skipped.is_empty() {
                    "none".to_owned()
                } else {
                    f.skipped.join(", ")
                };
                format!(
                    "{spp} · {:.0} ms/pass · {:.2} Mrays/s · skipped: {skipped}",
                    f.pass_ms, f.mrays
                )
            }
        };
        ui.horizontal(|ui| {
            ui.monospace(text);
            if !self.message.is_empty() {
                ui.separator();
                ui.label(&self.message);
            }
        });
    }
}
