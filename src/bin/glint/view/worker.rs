//! The render thread: renders the newest view one pass at a time and hands each
//! refined image to the window, so the window never waits for a pass.
//!
//! Each [`Job`] restarts accumulation ([`Renderer::restart`]): a quarter-resolution
//! pass first (a coarse frame at once), then full-resolution passes up to the
//! settings' samples per pixel. While the camera moves, only the coarse pass runs.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

use glam::Vec3;
use glint::Renderer;
use glint::scene::{Camera, Settings};

/// Reduction of each side for the coarse pass and while the camera moves.
pub const COARSE: u32 = 4;
/// Images at most this many pixels skip the coarse pass: their first full pass is quick.
const SMALL_IMAGE: u32 = 128 * 128;

/// Asks the window to repaint; set once the window exists, called after every report.
pub type Wake = Arc<Mutex<Option<Box<dyn Fn() + Send>>>>;

/// What to render: a view and its settings, numbered so that stale frames are dropped.
#[derive(Clone, Debug)]
pub struct Job {
    /// Increases with every change of the view or the settings.
    pub generation: u64,
    /// The camera at full resolution.
    pub camera: Camera,
    /// The settings.
    pub settings: Settings,
    /// The camera is moving: render only the coarse pass.
    pub moving: bool,
}

/// One refined image and what it cost.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The job it renders.
    pub generation: u64,
    /// Image width (a quarter of the view's for a coarse frame).
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Linear radiance, row-major.
    pub pixels: Vec<Vec3>,
    /// Samples per pixel reached (0 for a coarse frame).
    pub samples: u32,
    /// Samples per pixel the settings ask for.
    pub target: u32,
    /// Wall time of the last pass, in milliseconds.
    pub pass_ms: f64,
    /// Rays of the last pass per second, in millions.
    pub mrays: f64,
    /// The plan's skipped stages.
    pub skipped: Vec<String>,
    /// `glint info`'s report of the scene and its plan.
    pub info: String,
    /// The last pass of the job is done.
    pub done: bool,
    /// Whether this frame is the coarse one.
    pub coarse: bool,
}

/// What the render thread sends back.
#[derive(Debug)]
pub enum Report {
    /// A new image.
    Frame(Box<Frame>),
    /// A render failed (e.g. a setting the scene cannot render with).
    Error(u64, String),
}

/// The window's handle on the render thread.
pub struct Worker {
    jobs: Sender<Job>,
    /// Reports from the thread, newest last.
    pub reports: Receiver<Report>,
    interrupt: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    /// Starts the thread on `renderer`; `wake` is called after every report (it asks
    /// the window to repaint).
    pub fn spawn(renderer: Renderer, wake: Wake) -> Self {
        let (jobs, job_rx) = channel();
        let (report_tx, reports) = channel();
        let interrupt = Arc::new(AtomicBool::new(false));
        let flag = interrupt.clone();
        let thread = std::thread::Builder::new()
            .name("glint view render".into())
            .spawn(move || render_loop(renderer, job_rx, report_tx, flag, wake))
            .expect("spawning the render thread");
        Self {
            jobs,
            reports,
            interrupt,
            thread: Some(thread),
        }
    }

    /// Replaces whatever is rendering with `job`: the pass in flight stops after its
    /// current region.
    pub fn submit(&self, job: Job) {
        self.interrupt.store(true, Ordering::Relaxed);
        let _ = self.jobs.send(job);
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.interrupt.store(true, Ordering::Relaxed);
        // Closing the channel ends the loop.
        let (dead, _) = channel();
        self.jobs = dead;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The job in progress and how far it got.
struct Progress {
    job: Job,
    /// Next sample index; `None` while the coarse pass is due.
    next: Option<u32>,
    target: u32,
    info: String,
    skipped: Vec<String>,
}

fn render_loop(
    mut renderer: Renderer,
    jobs: Receiver<Job>,
    reports: Sender<Report>,
    interrupt: Arc<AtomicBool>,
    wake: Wake,
) {
    renderer.set_interrupt(interrupt.clone());
    let mut current: Option<Progress> = None;
    loop {
        // The newest job wins; wait for one only when there is nothing left to do.
        let mut newest = None;
        let idle = current.as_ref().is_none_or(|p| {
            p.next.is_some_and(|n| n >= p.target) || (p.job.moving && p.next.is_some())
        });
        if idle {
            match jobs.recv() {
                Ok(j) => newest = Some(j),
                Err(_) => return,
            }
        }
        loop {
            match jobs.try_recv() {
                Ok(j) => newest = Some(j),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return,
            }
        }
        if let Some(job) = newest {
            interrupt.store(false, Ordering::Relaxed);
            let small = job.camera.width * job.camera.height <= SMALL_IMAGE;
            current = Some(Progress {
                next: if small && !job.moving { Some(0) } else { None },
                target: 0,
                info: String::new(),
                skipped: Vec::new(),
                job,
            });
        }
        let Some(p) = current.as_mut() else { continue };
        let report = match step(&mut renderer, p) {
            Ok(Some(frame)) => Report::Frame(Box::new(frame)),
            Ok(None) => continue,
            Err(e) => {
                let r = Report::Error(p.job.generation, e.to_string());
                // Nothing more to do for this job until the next one arrives.
                p.next = Some(u32::MAX);
                p.target = 0;
                r
            }
        };
        if reports.send(report).is_err() {
            return;
        }
        if let Some(wake) = wake.lock().expect("wake lock").as_ref() {
            wake();
        }
    }
}

/// Renders the next pass of `p`; `None` when it was interrupted by a newer job.
fn step(renderer: &mut Renderer, p: &mut Progress) -> glint::Result<Option<Frame>> {
    let coarse = p.next.is_none();
    let mut camera = p.job.camera.clone();
    if coarse {
        camera.width = (camera.width / COARSE).max(1);
        camera.height = (camera.height / COARSE).max(1);
    }
    let sample = p.next.unwrap_or(0);
    if coarse || sample == 0 {
        renderer.restart(&camera, &p.job.settings);
        renderer.prepare()?;
        // The plan view describes the full-resolution camera once there is one.
        if p.info.is_empty() || !coarse {
            p.info = glint::info::describe(renderer)?;
            p.skipped = renderer
                .plan()
                .entries
                .iter()
                .filter(|e| !e.runs)
                .map(|e| e.stage.to_owned())
                .collect();
        }
        p.target = renderer.samples_per_pixel();
    }
    let rays_before = renderer.stats().rays.total();
    let start = Instant::now();
    renderer.render_pass(sample, &mut |_| {})?;
    if renderer.interrupted() {
        return Ok(None);
    }
    let seconds = start.elapsed().as_secs_f64();
    let rays = renderer.stats().rays.total() - rays_before;
    p.next = Some(if coarse { 0 } else { sample + 1 });
    let film = renderer.film();
    let done = !coarse && sample + 1 >= p.target || coarse && p.job.moving;
    Ok(Some(Frame {
        generation: p.job.generation,
        width: film.width,
        height: film.height,
        pixels: film.image(),
        samples: if coarse { 0 } else { sample + 1 },
        target: p.target,
        pass_ms: seconds * 1e3,
        mrays: rays as f64 / seconds.max(1e-9) / 1e6,
        skipped: p.skipped.clone(),
        info: p.info.clone(),
        done,
        coarse,
    }))
}
