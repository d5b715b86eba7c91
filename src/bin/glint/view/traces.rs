//! Traced pixels: `glint debug --pixel`'s trace of one pixel, its debug primitives drawn
//! over the view in 3D with the viewer's camera, and its `--dump` text.

use std::collections::BTreeSet;

use egui::{Align2, Color32, FontId, Painter, Pos2, Rect, Stroke, pos2, vec2};
use glam::{Vec2, Vec3};
use glint::debug::overlay::box_edges;
use glint::debug::{DebugPrimitive, DebugRequest, DebugSession, Feature, Shape};
use glint::scene::texture::Texture;
use glint::scene::{Camera, Settings};
use glint::trace::camera::CameraBasis;
use glint::trace::materials::Materials;

use super::scene::ViewScene;

/// Texels a side of a texture panel's image at most.
const PANEL_TEXELS: u32 = 256;

/// A texture the trace looked up, as the image of its panel.
#[derive(Clone)]
pub struct PanelImage {
    /// Index into the material table's textures.
    pub texture: u32,
    /// The texture, shrunk to at most [`PANEL_TEXELS`] a side.
    pub image: egui::ColorImage,
    /// The image once uploaded.
    pub handle: Option<egui::TextureHandle>,
}

/// One traced pixel and what its trace spawned.
#[derive(Clone)]
pub struct TracedPixel {
    /// The pixel `[x, y]` of the view it was traced in.
    pub pixel: [u32; 2],
    /// Its colour as the trace computed it.
    pub color: Vec3,
    /// The debug primitives, in spawn order.
    pub primitives: Vec<DebugPrimitive>,
    /// The same text `glint debug --dump` writes.
    pub dump: String,
    /// The textures of its texture panels.
    pub panels: Vec<PanelImage>,
}

/// Traces `pixel` of the view (`camera`, `settings`) exactly as `glint debug --pixel`
/// does on the scene saved with that view, every feature asked for.
pub fn trace_pixel(
    scene: &ViewScene,
    camera: &Camera,
    settings: &Settings,
    pixel: [u32; 2],
    bvh_level: Option<u32>,
) -> glint::Result<TracedPixel> {
    let file = scene.with_view(camera, settings);
    let mut request = DebugRequest::all(pixel[0], pixel[1]);
    request.bvh_level = bvh_level;
    let mut session = DebugSession::trace(&file, &scene.path, request)?;
    let primitives = session.primitives();
    let textures = &session.renderer.world.resource::<Materials>().textures;
    let panels = primitives
        .iter()
        .filter_map(|p| match &p.shape {
            Shape::TexturePanel { texture, .. } => {
                let t = textures.get(*texture as usize)?;
                Some(PanelImage {
                    texture: *texture,
                    image: panel_image(t),
                    handle: None,
                })
            }
            _ => None,
        })
        .collect();
    Ok(TracedPixel {
        pixel,
        color: session.pixel_color(),
        dump: session.dump_ron()?,
        primitives,
        panels,
    })
}

/// `t` as an image of at most [`PANEL_TEXELS`] a side (nearest texel), row 0 at the top.
fn panel_image(t: &Texture) -> egui::ColorImage {
    let scale = (PANEL_TEXELS as f32 / t.width.max(t.height).max(1) as f32).min(1.0);
    let w = ((t.width as f32 * scale) as u32).max(1);
    let h = ((t.height as f32 * scale) as u32).max(1);
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for j in 0..h {
        for i in 0..w {
            let x = ((i as f32 / scale) as u32).min(t.width.saturating_sub(1));
            let y = ((j as f32 / scale) as u32).min(t.height.saturating_sub(1));
            let c = t
                .texels
                .get((y * t.width + x) as usize)
                .copied()
                .unwrap_or_default();
            rgb.extend(
                c.to_array()
                    .map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8),
            );
        }
    }
    egui::ColorImage::from_rgb([w as usize, h as usize], &rgb)
}

/// A linear debug colour as egui's.
fn color(c: Vec3) -> Color32 {
    let b = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    Color32::from_rgb(b(c.x), b(c.y), b(c.z))
}

/// Maps world points to the screen through the view's camera.
pub struct Projector {
    basis: CameraBasis,
    rect: Rect,
    /// Points nearer than this to the eye are clipped away.
    near: f32,
}

impl Projector {
    /// The projection of `camera` onto `rect` (the image on screen).
    pub fn new(camera: &Camera, rect: Rect) -> Self {
        let basis = CameraBasis::new(camera);
        let distance = (camera.look_at - camera.position).length();
        Self {
            basis,
            rect,
            near: 1e-3 * distance.max(1e-6),
        }
    }

    /// Screen position of `p`, if it is in front of the eye.
    pub fn point(&self, p: Vec3) -> Option<Pos2> {
        if self.basis.depth(p) < self.near {
            return None;
        }
        let (x, y, _) = self.basis.project(p)?;
        let r = self.rect;
        Some(pos2(
            r.min.x + x / self.basis.width * r.width(),
            r.min.y + y / self.basis.height * r.height(),
        ))
    }

    /// The part of segment `a`..`b` in front of the eye, on screen.
    pub fn segment(&self, a: Vec3, b: Vec3) -> Option<[Pos2; 2]> {
        let (da, db) = (self.basis.depth(a), self.basis.depth(b));
        if da < self.near && db < self.near {
            return None;
        }
        let clip = |p: Vec3, q: Vec3, dp: f32, dq: f32| {
            if dp >= self.near {
                p
            } else {
                p + (q - p) * ((self.near - dp) / (dq - dp))
            }
        };
        Some([
            self.point(clip(a, b, da, db))?,
            self.point(clip(b, a, db, da))?,
        ])
    }

    /// Screen length of a world length `r` at `p`.
    fn radius(&self, p: Vec3, r: f32) -> f32 {
        let z = self.basis.depth(p).max(self.near);
        r / self.basis.height_at(z) * self.rect.height()
    }
}

/// Draws the primitives of `traces` whose feature is in `shown` over the image.
pub fn draw_traces(
    painter: &Painter,
    proj: &Projector,
    traces: &mut [TracedPixel],
    shown: &BTreeSet<Feature>,
) {
    for (i, t) in traces.iter_mut().enumerate() {
        let TracedPixel {
            primitives, panels, ..
        } = t;
        let mut inset = 0;
        for p in primitives.iter().filter(|p| shown.contains(&p.feature)) {
            let c = color(p.color);
            let stroke = Stroke::new(1.5, c);
            match &p.shape {
                Shape::Segment { a, b } => {
                    if let Some(s) = proj.segment(*a, *b) {
                        painter.line_segment(s, stroke);
                    }
                }
                Shape::Marker { center, radius } => {
                    if let Some(s) = proj.point(*center) {
                        painter.circle_filled(s, proj.radius(*center, *radius).clamp(3.0, 40.0), c);
                    }
                }
                Shape::Box { min, max } => {
                    for (a, b) in box_edges(*min, *max) {
                        if let Some(s) = proj.segment(a, b) {
                            painter.line_segment(s, Stroke::new(1.0, c));
                        }
                    }
                }
                Shape::Label { at: Some(at), text } => {
                    if let Some(s) = proj.point(*at) {
                        painter.text(s, Align2::LEFT_BOTTOM, text, FontId::monospace(11.0), c);
                    }
                }
                Shape::Label { at: None, .. } => {}
                Shape::TexturePanel {
                    texture,
                    size,
                    uv,
                    texels,
                } => {
                    let r = inset_rect(proj.rect, i, inset);
                    inset += 1;
                    painter.rect_filled(r, 0.0, Color32::from_black_alpha(200));
                    if let Some(panel) = panels.iter_mut().find(|p| p.texture == *texture) {
                        let handle = panel.handle.get_or_insert_with(|| {
                            painter.ctx().load_texture(
                                format!("texture panel {i} {texture}"),
                                panel.image.clone(),
                                egui::TextureOptions::NEAREST,
                            )
                        });
                        let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0));
                        painter.image(handle.id(), r, uv, Color32::WHITE);
                    }
                    draw_texture_panel(painter, r, *size, *uv, texels, c);
                }
                Shape::SampleGrid { strata, points } => {
                    let r = inset_rect(proj.rect, i, inset);
                    inset += 1;
                    draw_sample_grid(painter, r, *strata, points, c);
                }
            }
        }
    }
}

/// Where the 2D insets go: the image's bottom-left corner, one column per trace.
fn inset_rect(image: Rect, trace: usize, inset: usize) -> Rect {
    let side = (image.height() * 0.22).clamp(60.0, 160.0);
    let min = pos2(
        image.min.x + 8.0 + inset as f32 * (side + 8.0),
        image.max.y - 8.0 - side - trace as f32 * (side + 8.0),
    );
    Rect::from_min_size(min, vec2(side, side))
}

/// The texture as a grid of its texels (capped), the texels read and the uv looked up.
fn draw_texture_panel(
    painter: &Painter,
    r: Rect,
    size: [u32; 2],
    uv: Vec2,
    texels: &[([u32; 2], f32)],
    c: Color32,
) {
    painter.rect_stroke(r, 0.0, Stroke::new(1.0, c), egui::StrokeKind::Inside);
    let (w, h) = (size[0].max(1) as f32, size[1].max(1) as f32);
    for ([x, y], weight) in texels {
        let cell = Rect::from_min_max(
            pos2(
                r.min.x + *x as f32 / w * r.width(),
                r.min.y + *y as f32 / h * r.height(),
            ),
            pos2(
                r.min.x + (*x + 1) as f32 / w * r.width(),
                r.min.y + (*y + 1) as f32 / h * r.height(),
            ),
        )
        .expand(1.5);
        painter.rect_stroke(
            cell,
            0.0,
            Stroke::new(1.0 + 2.0 * weight, c),
            egui::StrokeKind::Outside,
        );
    }
    // v = 0 is the image's bottom row.
    let p = pos2(
        r.min.x + uv.x.fract() * r.width(),
        r.max.y - uv.y.fract() * r.height(),
    );
    painter.circle_stroke(p, 3.0, Stroke::new(1.0, Color32::WHITE));
    painter.text(
        r.left_top() + vec2(2.0, 2.0),
        Align2::LEFT_TOP,
        format!("{}x{} uv {:.3},{:.3}", size[0], size[1], uv.x, uv.y),
        FontId::monospace(10.0),
        Color32::WHITE,
    );
}

/// The pixel as a square with its strata and sample positions.
fn draw_sample_grid(painter: &Painter, r: Rect, strata: Option<u32>, points: &[Vec2], c: Color32) {
    painter.rect_filled(r, 0.0, Color32::from_black_alpha(200));
    painter.rect_stroke(r, 0.0, Stroke::new(1.0, c), egui::StrokeKind::Inside);
    if let Some(k) = strata {
        let grid = Stroke::new(0.5, Color32::GRAY);
        for i in 1..k {
            let f = i as f32 / k as f32;
            painter.line_segment(
                [
                    pos2(r.min.x + f * r.width(), r.min.y),
                    pos2(r.min.x + f * r.width(), r.max.y),
                ],
                grid,
            );
            painter.line_segment(
                [
                    pos2(r.min.x, r.min.y + f * r.height()),
                    pos2(r.max.x, r.min.y + f * r.height()),
                ],
                grid,
            );
        }
    }
    for p in points {
        painter.circle_filled(
            pos2(r.min.x + p.x * r.width(), r.min.y + p.y * r.height()),
            2.5,
            c,
        );
    }
}
