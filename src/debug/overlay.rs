//! The overlay rasteriser: draws debug primitives over a background image through the
//! view camera, with 2D insets for panels, a legend and a caption. Text uses the
//! 8x8 bitmap font of [`crate::film::text`], so no system fonts are needed.

use glam::{Vec2, Vec3};

use super::primitives::{DebugPrimitive, Shape};
use super::view::ViewCamera;
use crate::film::text::for_each_dot;
use crate::shade::texture::Texture;

/// Side of a panel inset in pixels.
const PANEL: i32 = 170;
/// Margin between insets and the image border.
const MARGIN: i32 = 8;
/// Opacity of the parts of primitives the scene hides (with the depth test on).
const HIDDEN_ALPHA: f32 = 0.25;

/// An RGB image in linear values, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Canvas {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels.
    pub pixels: Vec<Vec3>,
}

impl Canvas {
    /// A canvas filled with `color`.
    pub fn new(width: u32, height: u32, color: Vec3) -> Self {
        Self {
            width,
            height,
            pixels: vec![color; width as usize * height as usize],
        }
    }

    /// The pixel at `(x, y)`.
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Blends `color` into pixel `(x, y)` with opacity `alpha`; outside pixels are ignored.
    pub fn blend(&mut self, x: i32, y: i32, color: Vec3, alpha: f32) {
        if x < 0 || y < 0 || x >= self.width as i32 || y >= self.height as i32 {
            return;
        }
        let p = &mut self.pixels[y as usize * self.width as usize + x as usize];
        *p = p.lerp(color, alpha);
    }

    /// A filled rectangle.
    pub fn fill_rect(&mut self, x: i32, y: i32, w: i32, h: i32, color: Vec3, alpha: f32) {
        for j in y..y + h {
            for i in x..x + w {
                self.blend(i, j, color, alpha);
            }
        }
    }

    /// A one-pixel rectangle outline.
    pub fn rect(&mut self, x: i32, y: i32, w: i32, h: i32, color: Vec3) {
        for i in x..x + w {
            self.blend(i, y, color, 1.0);
            self.blend(i, y + h - 1, color, 1.0);
        }
        for j in y..y + h {
            self.blend(x, j, color, 1.0);
            self.blend(x + w - 1, j, color, 1.0);
        }
    }

    /// A filled disc.
    pub fn disc(&mut self, c: Vec2, r: f32, color: Vec3, alpha: f32) {
        let ri = r.ceil() as i32 + 1;
        let (cx, cy) = (c.x.floor() as i32, c.y.floor() as i32);
        for j in -ri..=ri {
            for i in -ri..=ri {
                let p = Vec2::new((cx + i) as f32 + 0.5, (cy + j) as f32 + 0.5);
                if p.distance(c) <= r {
                    self.blend(cx + i, cy + j, color, alpha);
                }
            }
        }
    }

    /// A line from `a` to `b` of the given width, with a per-pixel opacity from `alpha(s)`
    /// for the parameter `s` in [0, 1] along it.
    pub fn line(
        &mut self,
        a: Vec2,
        b: Vec2,
        width: f32,
        color: Vec3,
        mut alpha: impl FnMut(f32) -> f32,
    ) {
        let len = a.distance(b);
        if !len.is_finite() {
            return;
        }
        // Lines far off screen are cut to a generous box so the loop stays bounded.
        let steps = (len.min(8.0 * (self.width + self.height) as f32))
            .ceil()
            .max(1.0) as i32;
        let r = (width * 0.5).max(0.5);
        for k in 0..=steps {
            let s = k as f32 / steps as f32;
            let p = a.lerp(b, s);
            if p.x < -r || p.y < -r || p.x > self.width as f32 + r || p.y > self.height as f32 + r {
                continue;
            }
            let o = alpha(s);
            if width <= 1.0 {
                self.blend(p.x.floor() as i32, p.y.floor() as i32, color, o);
            } else {
                self.disc(p, r, color, o);
            }
        }
    }

    /// Text in the 8x8 font at `(x, y)` (top-left), `scale` pixels per font pixel.
    pub fn text(&mut self, x: i32, y: i32, text: &str, color: Vec3, scale: i32) {
        for_each_dot(text, |fx, fy| {
            self.fill_rect(x + fx * scale, y + fy * scale, scale, scale, color, 1.0);
        });
    }

    /// Text on a dark backing box, for legibility over any background.
    pub fn label(&mut self, x: i32, y: i32, text: &str, color: Vec3) {
        let w = 8 * text.chars().count() as i32 + 4;
        self.fill_rect(x - 2, y - 2, w, 12, Vec3::ZERO, 0.7);
        self.text(x, y, text, color, 1);
    }
}

/// How to draw: the view, the scene's depth from it (for the optional depth test) and
/// the textures panels refer to.
pub struct OverlayInput<'a> {
    /// The view camera.
    pub view: &'a ViewCamera,
    /// View-space depth of the scene at each view pixel (`INFINITY` where nothing is hit).
    pub scene_depth: Option<&'a [f32]>,
    /// Textures, indexed as in `Materials::textures`.
    pub textures: &'a [std::sync::Arc<Texture>],
}

impl OverlayInput<'_> {
    /// Opacity for a point at `(p, z)`: 1 if visible, [`HIDDEN_ALPHA`] if the scene is in front.
    fn depth_alpha(&self, p: Vec2, z: f32) -> f32 {
        let Some(depth) = self.scene_depth else {
            return 1.0;
        };
        let (w, h) = (self.view.camera.width, self.view.camera.height);
        if p.x < 0.0 || p.y < 0.0 || p.x >= w as f32 || p.y >= h as f32 {
            return 1.0;
        }
        let d = depth[p.y as usize * w as usize + p.x as usize];
        // A little slack so primitives lying on surfaces stay visible.
        if z <= d * 1.002 + self.view.near {
            1.0
        } else {
            HIDDEN_ALPHA
        }
    }

    fn segment(&self, canvas: &mut Canvas, a: Vec3, b: Vec3, width: f32, color: Vec3) {
        let Some(((pa, za), (pb, zb))) = self.view.project_segment(a, b) else {
            return;
        };
        // 1/z is linear in screen space: interpolate it for the depth along the line.
        let (ia, ib) = (1.0 / za, 1.0 / zb);
        canvas.line(pa, pb, width, color, |s| {
            let z = 1.0 / (ia + (ib - ia) * s);
            self.depth_alpha(pa.lerp(pb, s), z)
        });
    }
}

/// Draws every primitive over `canvas`: the world-space ones, then the insets, caption and legend.
pub fn draw_primitives(canvas: &mut Canvas, input: &OverlayInput, prims: &[&DebugPrimitive]) {
    draw_world(canvas, input, prims);
    draw_insets(canvas, input, prims);
    draw_caption(canvas, prims);
    draw_legend(canvas, prims);
}

/// Draws the world-space primitives (boxes, segments, markers, anchored labels) through the view.
pub fn draw_world(canvas: &mut Canvas, input: &OverlayInput, prims: &[&DebugPrimitive]) {
    // Boxes under rays under markers, so the thin structure does not hide the path.
    for p in prims {
        if let Shape::Box { min, max } = p.shape {
            for (a, b) in box_edges(min, max) {
                input.segment(canvas, a, b, 1.0, p.color);
            }
        }
    }
    for p in prims {
        if let Shape::Segment { a, b } = p.shape {
            input.segment(canvas, a, b, 2.0, p.color);
        }
    }
    for p in prims {
        if let Shape::Marker { center, radius } = p.shape
            && let Some((c, z)) = input.view.project(center)
        {
            let r = (radius * input.view.pixels_per_unit(z)).clamp(3.0, 10.0);
            let alpha = input.depth_alpha(c, z);
            canvas.disc(c, r + 1.0, Vec3::ZERO, alpha);
            canvas.disc(c, r, p.color, alpha);
        }
    }
    for p in prims {
        if let Shape::Label { at: Some(at), text } = &p.shape
            && let Some((c, _)) = input.view.project(*at)
        {
            canvas.label(c.x as i32 + 6, c.y as i32 - 4, text, p.color);
        }
    }
}

/// The 12 edges of a box.
pub fn box_edges(min: Vec3, max: Vec3) -> Vec<(Vec3, Vec3)> {
    let c = |i: u32| {
        Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    };
    let mut edges = Vec::with_capacity(12);
    for i in 0..8u32 {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                edges.push((c(i), c(i | bit)));
            }
        }
    }
    edges
}

/// Panels along the bottom edge, right to left.
fn draw_insets(canvas: &mut Canvas, input: &OverlayInput, prims: &[&DebugPrimitive]) {
    let mut x = canvas.width as i32 - MARGIN - PANEL;
    let y = canvas.height as i32 - MARGIN - PANEL;
    for p in prims {
        let drawn = match &p.shape {
            Shape::TexturePanel {
                texture,
                uv,
                texels,
                ..
            } => match input.textures.get(*texture as usize) {
                Some(tex) => {
                    texture_panel(canvas, x, y, tex, *uv, texels);
                    true
                }
                None => false,
            },
            Shape::SampleGrid { strata, points } => {
                sample_panel(canvas, x, y, *strata, points, p.color);
                true
            }
            _ => false,
        };
        if drawn {
            canvas.label(x, y - 14, p.values.what, Vec3::ONE);
            x -= PANEL + MARGIN;
            if x < 0 {
                break;
            }
        }
    }
}

/// The texture scaled into a square inset, the read texels outlined, the lookup point dotted.
fn texture_panel(
    canvas: &mut Canvas,
    x0: i32,
    y0: i32,
    tex: &Texture,
    uv: Vec2,
    texels: &[([u32; 2], f32)],
) {
    let (tw, th) = (tex.width.max(1) as f32, tex.height.max(1) as f32);
    let scale = (PANEL as f32 / tw).min(PANEL as f32 / th);
    let (w, h) = ((tw * scale) as i32, (th * scale) as i32);
    canvas.fill_rect(x0 - 2, y0 - 2, PANEL + 4, PANEL + 4, Vec3::ZERO, 1.0);
    for j in 0..h {
        for i in 0..w {
            let c = tex.texel((i as f32 / scale) as u32, (j as f32 / scale) as u32);
            canvas.blend(x0 + i, y0 + j, c, 1.0);
        }
    }
    for &([i, j], weight) in texels {
        let (rx, ry) = ((i as f32 * scale) as i32, (j as f32 * scale) as i32);
        let side = scale.ceil().max(3.0) as i32;
        let color = Vec3::ONE.lerp(Vec3::new(1.0, 0.2, 0.8), 1.0 - weight);
        canvas.rect(x0 + rx - 1, y0 + ry - 1, side + 2, side + 2, Vec3::ZERO);
        canvas.rect(x0 + rx, y0 + ry, side, side, color);
    }
    // The lookup point: u from the left, v from the bottom (SPEC "Textures").
    let p = Vec2::new(
        x0 as f32 + uv.x.clamp(0.0, 1.0) * w as f32,
        y0 as f32 + (1.0 - uv.y.clamp(0.0, 1.0)) * h as f32,
    );
    canvas.disc(p, 3.5, Vec3::ZERO, 1.0);
    canvas.disc(p, 2.5, Vec3::new(0.15, 0.3, 1.0), 1.0);
}

/// The pixel as a square with its strata and sample points.
fn sample_panel(
    canvas: &mut Canvas,
    x0: i32,
    y0: i32,
    strata: Option<u32>,
    points: &[Vec2],
    color: Vec3,
) {
    canvas.fill_rect(x0, y0, PANEL, PANEL, Vec3::splat(0.92), 1.0);
    if let Some(k) = strata {
        for i in 1..k {
            let o = (i as f32 / k as f32 * PANEL as f32) as i32;
            canvas.fill_rect(x0 + o, y0, 1, PANEL, Vec3::splat(0.55), 1.0);
            canvas.fill_rect(x0, y0 + o, PANEL, 1, Vec3::splat(0.55), 1.0);
        }
    }
    canvas.rect(x0, y0, PANEL, PANEL, Vec3::ZERO);
    for p in points {
        let c = Vec2::new(x0 as f32, y0 as f32) + *p * PANEL as f32;
        canvas.disc(c, 3.0, color, 1.0);
    }
}

/// Caption labels (no anchor) along the top edge, right of the legend.
fn draw_caption(canvas: &mut Canvas, prims: &[&DebugPrimitive]) {
    let mut y = MARGIN;
    for p in prims {
        if let Shape::Label { at: None, text } = &p.shape {
            let x = canvas.width as i32 - MARGIN - 8 * text.chars().count() as i32;
            canvas.label(x.max(MARGIN), y, text, Vec3::ONE);
            canvas.fill_rect(x.max(MARGIN) - 14, y, 10, 8, p.color, 1.0);
            y += 14;
        }
    }
}

/// The legend key of a primitive: what it is, and the level where colours encode it.
fn legend_key(p: &DebugPrimitive) -> String {
    match (p.values.what, p.values.depth) {
        ("reflection ray", Some(d)) => format!("reflection depth {d}"),
        ("bvh node" | "bvh level", Some(d)) => format!("bvh depth {d}"),
        ("light sample", Some(_)) if p.values.visible == Some(false) => "blocked light".into(),
        (what, _) => what.to_owned(),
    }
}

/// One swatch per kind of primitive drawn, top-left.
fn draw_legend(canvas: &mut Canvas, prims: &[&DebugPrimitive]) {
    let mut entries: Vec<(String, Vec3)> = Vec::new();
    for p in prims {
        if matches!(p.shape, Shape::Label { .. }) {
            continue;
        }
        let key = legend_key(p);
        if !entries.iter().any(|(k, _)| *k == key) {
            entries.push((key, p.color));
        }
    }
    let max_rows = ((canvas.height as i32 - 2 * MARGIN) / 12).max(1) as usize;
    let mut y = MARGIN;
    for (key, color) in entries.iter().take(max_rows) {
        canvas.fill_rect(
            MARGIN - 2,
            y - 2,
            8 * key.len() as i32 + 20,
            12,
            Vec3::ZERO,
            0.7,
        );
        canvas.fill_rect(MARGIN, y, 10, 8, *color, 1.0);
        canvas.rect(MARGIN, y, 10, 8, Vec3::splat(0.5));
        canvas.text(MARGIN + 14, y, key, Vec3::ONE, 1);
        y += 12;
    }
}
