//! The side panel: camera, every render setting of docs/scene-format.md, the plan,
//! the debug features and traced pixels, saving.

use std::path::Path;

use egui::{ComboBox, DragValue, RichText, Slider, Ui};
use glint::debug::Feature;
use glint::scene::validate::validate_settings;
use glint::scene::{Acceleration, BvhSplit, PixelSampling, Settings, ShadingModel};

use super::app::Viewer;

/// Keys and mouse, for the panel's help line.
const HELP: &str = "drag: orbit · shift/right drag: pan · wheel: zoom · WASD/QE: fly · Home: reset · \
                    R or click: trace the pixel under the cursor · C: clear traces";

impl Viewer {
    /// The side panel's sections.
    pub(super) fn side_panel(&mut self, ui: &mut Ui) {
        ui.heading("Camera");
        ui.label(RichText::new(HELP).small());
        ui.add(Slider::new(&mut self.camera.fov_y_degrees, 5.0..=120.0).text("field of view"));
        if ui.button("reset camera (Home)").clicked() {
            self.reset_camera();
        }
        ui.separator();
        ui.heading("Settings");
        settings_ui(ui, &mut self.settings, &mut self.gradient_text);
        ui.separator();
        egui::CollapsingHeader::new("Plan (glint info)")
            .default_open(true)
            .show(ui, |ui| {
                let info = self.frame.as_ref().map_or("", |f| f.info.as_str());
                ui.label(RichText::new(info).monospace().small());
            });
        ui.separator();
        ui.heading("Debug");
        ui.horizontal_wrapped(|ui| {
            for f in Feature::ALL {
                let mut on = self.shown.contains(&f);
                if ui.checkbox(&mut on, f.name()).changed() {
                    if on {
                        self.shown.insert(f);
                    } else {
                        self.shown.remove(&f);
                    }
                }
            }
        });
        ui.horizontal(|ui| {
            let mut on = self.bvh_level.is_some();
            let label = ui.checkbox(&mut on, "BVH level");
            let mut level = self.bvh_level.unwrap_or(2);
            ui.add_enabled(on, DragValue::new(&mut level).range(0..=32))
                .labelled_by(label.id);
            self.bvh_level = on.then_some(level);
        });
        if ui.button("clear traced pixels (C)").clicked() {
            self.traces.clear();
        }
        let mut remove = None;
        for (i, t) in self.traces.iter().enumerate() {
            let title = format!(
                "pixel {},{} = ({:.3}, {:.3}, {:.3}), {} entities",
                t.pixel[0],
                t.pixel[1],
                t.color.x,
                t.color.y,
                t.color.z,
                t.primitives.len()
            );
            egui::CollapsingHeader::new(title)
                .id_salt(("trace", i))
                .show(ui, |ui| {
                    if ui.small_button("remove").clicked() {
                        remove = Some(i);
                    }
                    ui.label(RichText::new(&t.dump).monospace().small());
                });
        }
        if let Some(i) = remove {
            self.traces.remove(i);
        }
        ui.separator();
        ui.heading("Save");
        ui.horizontal(|ui| {
            let label = ui.label("image");
            ui.add(egui::TextEdit::singleline(&mut self.image_path).desired_width(150.0))
                .labelled_by(label.id);
            if ui.button("save image").clicked() {
                let path = self.image_path.clone();
                self.message = match self.save_image(&path) {
                    Ok(()) => format!("wrote {path}"),
                    Err(e) => e.to_string(),
                };
            }
        });
        ui.horizontal(|ui| {
            let label = ui.label("scene");
            ui.add(egui::TextEdit::singleline(&mut self.scene_path).desired_width(150.0))
                .labelled_by(label.id);
            if ui.button("save scene").clicked() {
                let path = self.scene_path.clone();
                self.message = match self.save_scene(&path) {
                    Ok(()) => format!("wrote {path}"),
                    Err(e) => e.to_string(),
                };
            }
        });
    }
}

/// A combo box over the values of a setting, named as the scene format names them.
fn choice<T: PartialEq + Copy>(ui: &mut Ui, label: &str, value: &mut T, options: &[(T, &str)]) {
    let current = options.iter().find(|o| o.0 == *value).map_or("?", |o| o.1);
    ComboBox::from_label(label)
        .selected_text(current)
        .show_ui(ui, |ui| {
            for (v, name) in options {
                ui.selectable_value(value, *v, *name);
            }
        });
}

/// Every field of [`Settings`], each labelled with its key in the scene format.
fn settings_ui(ui: &mut Ui, s: &mut Settings, gradients: &mut [String; 2]) {
    ui.checkbox(&mut s.shading, "shading");
    choice(
        ui,
        "shading_model",
        &mut s.shading_model,
        &[
            (ShadingModel::Lambertian, "lambertian"),
            (ShadingModel::Phong, "phong"),
            (ShadingModel::BlinnPhong, "blinn_phong"),
            (ShadingModel::LinearGradient, "linear_gradient"),
            (
                ShadingModel::LinearGradientComparison,
                "linear_gradient_comparison",
            ),
        ],
    );
    for (key, text) in ["gradient", "comparison_gradient"]
        .into_iter()
        .zip(gradients.iter_mut())
    {
        ui.horizontal(|ui| {
            let label = ui.label(key);
            let edit = ui
                .add(egui::TextEdit::singleline(text).desired_width(150.0))
                .labelled_by(label.id);
            if edit.lost_focus() {
                // A value that does not parse or validate leaves the setting as it was.
                let mut changed = s.clone();
                if changed.set(key, text).is_ok()
                    && validate_settings(&changed, Path::new(key)).is_ok()
                {
                    *s = changed;
                }
            }
        });
    }
    ui.checkbox(&mut s.reflections, "reflections");
    ui.checkbox(&mut s.transparency, "transparency");
    ui.checkbox(&mut s.shadows, "shadows");
    ui.checkbox(&mut s.normal_interpolation, "normal_interpolation");
    ui.checkbox(&mut s.texture_mapping, "texture_mapping");
    ui.checkbox(&mut s.bilinear_filtering, "bilinear_filtering");
    choice(
        ui,
        "acceleration",
        &mut s.acceleration,
        &[(Acceleration::Bvh, "bvh"), (Acceleration::None, "none")],
    );
    choice(
        ui,
        "bvh_split",
        &mut s.bvh_split,
        &[
            (BvhSplit::SahBinned, "sah_binned"),
            (BvhSplit::Median, "median"),
        ],
    );
    ui.add(
        DragValue::new(&mut s.pixel_samples)
            .range(1..=4096)
            .prefix("pixel_samples "),
    );
    choice(
        ui,
        "pixel_sampling",
        &mut s.pixel_sampling,
        &[
            (PixelSampling::Uniform, "uniform"),
            (PixelSampling::Stratified, "stratified"),
        ],
    );
    ui.add(
        DragValue::new(&mut s.shadow_samples)
            .range(1..=256)
            .prefix("shadow_samples "),
    );
    ui.add(
        DragValue::new(&mut s.max_depth)
            .range(0..=64)
            .prefix("max_depth "),
    );
    ui.add(DragValue::new(&mut s.seed).prefix("seed "));
    ui.horizontal(|ui| {
        let mut rgb = s.background.to_array();
        ui.color_edit_button_rgb(&mut rgb);
        ui.label("background");
        s.background = rgb.into();
    });
}
