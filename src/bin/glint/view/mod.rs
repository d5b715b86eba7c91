//! `glint view` (feature `view`): the interactive viewer. A window shows the scene
//! rendering progressively on a background thread ([`worker`]), moved with the mouse and
//! keys ([`controls`]), with a panel of every setting and the plan ([`panel`]); `R` or a
//! click traces the pixel under the cursor as `glint debug --pixel` does and draws its
//! debug primitives over the view in 3D ([`traces`]). The view saves as an image or as
//! a RON scene ([`scene`]).
//!
//! It uses only the library's public API, so `tests/view.rs` includes it by path.

pub mod app;
pub mod controls;
pub mod panel;
pub mod scene;
pub mod traces;
pub mod worker;

use std::path::Path;

use app::PANEL_WIDTH;
pub use app::Viewer;
pub use scene::ViewScene;

/// Height of the status line, in points.
const STATUS_HEIGHT: f32 = 24.0;

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.show(ui);
    }
}

/// Opens the window on `path` (a RON scene or a glTF/OBJ model). Its image area starts
/// at the scene camera's size and follows the window's.
pub fn run(path: &Path, overrides: &glint::Overrides) -> Result<(), String> {
    let scene = ViewScene::load(path, overrides).map_err(|e| e.to_string())?;
    let camera = scene.camera();
    let viewer = Viewer::new(scene).map_err(|e| e.to_string())?;
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(format!("glint view {}", path.display()))
            .with_inner_size([
                camera.width as f32 + PANEL_WIDTH,
                camera.height as f32 + STATUS_HEIGHT,
            ]),
        ..Default::default()
    };
    eframe::run_native(
        "glint view",
        options,
        Box::new(move |_cc| Ok(Box::new(viewer))),
    )
    .map_err(|e| format!("cannot open the viewer's window: {e}"))
}
