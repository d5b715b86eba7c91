//! The convergence plot: RMSE against seconds and against spp on log-log axes, drawn
//! with `image` and the 8x8 bitmap font of [`crate::film::text`], so that it needs no
//! system font and no plotting backend.

use std::path::Path;

use image::{Rgb, RgbImage};

use super::Curve;
use crate::error::{GlintError, Result};
use crate::film::text::for_each_dot;
use crate::film::write_atomically;

/// Canvas width in pixels.
const WIDTH: u32 = 1400;
/// Height of each panel (title, plot area and x labels).
const PANEL_HEIGHT: u32 = 560;
/// Glyph scale: 8x8 glyphs drawn as 16x16.
const SCALE: u32 = 2;
/// Glyph advance in pixels.
const GLYPH: i32 = 8 * SCALE as i32;
/// Legend line height.
const LEGEND_ROW: u32 = 26;
/// Plot-area margins inside a panel: left, right, top, bottom.
const MARGIN: (i32, i32, i32, i32) = (110, 44, 44, 76);

/// Tableau 10: distinguishable curve colours.
const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];
const BLACK: Rgb<u8> = Rgb([0, 0, 0]);
const GRID: Rgb<u8> = Rgb([225, 225, 225]);
const MINOR_GRID: Rgb<u8> = Rgb([243, 243, 243]);
const WHITE: Rgb<u8> = Rgb([255, 255, 255]);

/// The colour of curve `i`.
pub fn curve_color(i: usize) -> Rgb<u8> {
    Rgb(PALETTE[i % PALETTE.len()])
}

fn put(img: &mut RgbImage, x: i32, y: i32, c: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, c);
    }
}

fn fill_rect(img: &mut RgbImage, x0: i32, y0: i32, x1: i32, y1: i32, c: Rgb<u8>) {
    for y in y0..y1 {
        for x in x0..x1 {
            put(img, x, y, c);
        }
    }
}

/// A line of `width` pixels: square stamps every half pixel along it.
fn line(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), width: i32, c: Rgb<u8>) {
    let len = (b.0 - a.0).hypot(b.1 - a.1);
    let steps = (len * 2.0).ceil().max(1.0) as i32;
    let lo = -(width - 1) / 2;
    for i in 0..=steps {
        let t = f64::from(i) / f64::from(steps);
        let x = (a.0 + t * (b.0 - a.0)).round() as i32;
        let y = (a.1 + t * (b.1 - a.1)).round() as i32;
        fill_rect(img, x + lo, y + lo, x + lo + width, y + lo + width, c);
    }
}

/// Text with its top-left corner at (x, y), left to right.
fn text(img: &mut RgbImage, x: i32, y: i32, s: &str, c: Rgb<u8>) {
    let scale = SCALE as i32;
    for_each_dot(s, |fx, fy| {
        let (px, py) = (x + fx * scale, y + fy * scale);
        fill_rect(img, px, py, px + scale, py + scale, c);
    });
}

/// Text rotated a quarter turn counter-clockwise (read bottom to top), starting at
/// the bottom-left corner (x, y).
fn text_up(img: &mut RgbImage, x: i32, y: i32, s: &str, c: Rgb<u8>) {
    let scale = SCALE as i32;
    for_each_dot(s, |fx, fy| {
        // Font pixel (fx, fy) goes to (fy, -fx) along the upward baseline.
        let (px, py) = (x + fy * scale, y - (fx + 1) * scale);
        fill_rect(img, px, py, px + scale, py + scale, c);
    });
}

fn text_width(s: &str) -> i32 {
    s.chars().count() as i32 * GLYPH
}

/// A log10 axis spanning whole decades around the data.
#[derive(Clone, Copy, Debug)]
struct LogAxis {
    lo: i32,
    hi: i32,
}

impl LogAxis {
    fn around(values: impl Iterator<Item = f64>) -> Self {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| *v > 0.0 && v.is_finite()) {
            lo = lo.min(v.log10());
            hi = hi.max(v.log10());
        }
        if !lo.is_finite() {
            return Self { lo: 0, hi: 1 };
        }
        let (lo, mut hi) = (lo.floor() as i32, hi.ceil() as i32);
        if hi <= lo {
            hi = lo + 1;
        }
        Self { lo, hi }
    }

    /// Position of `v` in [0, 1] along the axis.
    fn frac(&self, v: f64) -> f64 {
        (v.log10() - f64::from(self.lo)) / f64::from(self.hi - self.lo)
    }

    /// Labelled ticks: decades, plus 2 and 5 when the axis spans at most two decades.
    fn labelled(&self) -> Vec<f64> {
        let mut ticks = Vec::new();
        for e in self.lo..=self.hi {
            let d = 10f64.powi(e);
            ticks.push(d);
            if self.hi - self.lo <= 2 && e < self.hi {
                ticks.extend([2.0 * d, 5.0 * d]);
            }
        }
        ticks
    }

    /// Unlabelled ticks at 2..9 times each decade.
    fn minor(&self) -> Vec<f64> {
        (self.lo..self.hi)
            .flat_map(|e| (2..10).map(move |m| f64::from(m) * 10f64.powi(e)))
            .collect()
    }
}

/// `0.01`, `1`, `200`, or `1e-5` outside [1e-3, 1e5).
fn tick_label(v: f64) -> String {
    if (1e-3..1e5).contains(&v) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        let e = v.log10().floor() as i32;
        let m = (v / 10f64.powi(e)).round();
        if m == 1.0 {
            format!("1e{e}")
        } else {
            format!("{m}e{e}")
        }
    }
}

/// One panel: RMSE (y) against `x_of` (x) for every curve.
struct Panel<'a> {
    title: &'a str,
    x_label: &'a str,
    x_of: fn(&super::PassRecord) -> f64,
    /// Also draw each curve's own error estimate, as a thin dashed line.
    estimates: bool,
}

fn draw_panel(img: &mut RgbImage, left: i32, panel: &Panel, curves: &[Curve], y_axis: LogAxis) {
    let width = (WIDTH / 2) as i32;
    let (ml, mr, mt, mb) = MARGIN;
    let (x0, x1) = (left + ml, left + width - mr);
    let (y0, y1) = (mt, PANEL_HEIGHT as i32 - mb);
    let x_axis = LogAxis::around(curves.iter().flat_map(|c| c.passes.iter().map(panel.x_of)));
    let px = |v: f64| f64::from(x0) + x_axis.frac(v) * f64::from(x1 - x0);
    let py = |v: f64| f64::from(y1) - y_axis.frac(v) * f64::from(y1 - y0);

    // Grid, then ticks and labels.
    for v in x_axis.minor() {
        line(
            img,
            (px(v), f64::from(y0)),
            (px(v), f64::from(y1)),
            1,
            MINOR_GRID,
        );
    }
    for v in y_axis.minor() {
        line(
            img,
            (f64::from(x0), py(v)),
            (f64::from(x1), py(v)),
            1,
            MINOR_GRID,
        );
    }
    for v in x_axis.labelled() {
        let x = px(v);
        line(img, (x, f64::from(y0)), (x, f64::from(y1)), 1, GRID);
        line(img, (x, f64::from(y1)), (x, f64::from(y1 + 6)), 1, BLACK);
        let s = tick_label(v);
        // Centred under the tick, but never past the canvas edge.
        let tx = (x as i32 - text_width(&s) / 2).min(WIDTH as i32 - text_width(&s) - 2);
        text(img, tx, y1 + 10, &s, BLACK);
    }
    for v in y_axis.labelled() {
        let y = py(v);
        line(img, (f64::from(x0), y), (f64::from(x1), y), 1, GRID);
        line(img, (f64::from(x0 - 6), y), (f64::from(x0), y), 1, BLACK);
        let s = tick_label(v);
        text(
            img,
            x0 - 10 - text_width(&s),
            y as i32 - GLYPH / 2,
            &s,
            BLACK,
        );
    }
    // Frame.
    let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)];
    for w in corners.windows(2) {
        let a = (f64::from(w[0].0), f64::from(w[0].1));
        let b = (f64::from(w[1].0), f64::from(w[1].1));
        line(img, a, b, 2, BLACK);
    }
    // Titles.
    text(
        img,
        (x0 + x1) / 2 - text_width(panel.title) / 2,
        12,
        panel.title,
        BLACK,
    );
    text(
        img,
        (x0 + x1) / 2 - text_width(panel.x_label) / 2,
        y1 + 10 + GLYPH + 14,
        panel.x_label,
        BLACK,
    );
    let y_label = "RMSE";
    text_up(
        img,
        left + 12,
        (y0 + y1) / 2 + text_width(y_label) / 2,
        y_label,
        BLACK,
    );
    // Curves, with a dot per measured pass when there are few.
    for (i, c) in curves.iter().enumerate() {
        let color = curve_color(i);
        let points: Vec<(f64, f64)> = c
            .passes
            .iter()
            .filter(|p| (panel.x_of)(p) > 0.0 && p.error.rmse > 0.0)
            .map(|p| (px((panel.x_of)(p)), py(p.error.rmse)))
            .collect();
        for w in points.windows(2) {
            line(img, w[0], w[1], 3, color);
        }
        if panel.estimates {
            let estimated: Vec<(f64, f64)> = c
                .passes
                .iter()
                .filter_map(|p| Some(((panel.x_of)(p), p.estimate?.rmse)))
                .filter(|&(x, e)| x > 0.0 && e > 0.0)
                .map(|(x, e)| (px(x), py(e)))
                .collect();
            for w in estimated.windows(2) {
                dashed(img, w[0], w[1], color);
            }
        }
        if points.len() <= 40 {
            for &(x, y) in &points {
                fill_rect(
                    img,
                    x as i32 - 3,
                    y as i32 - 3,
                    x as i32 + 4,
                    y as i32 + 4,
                    color,
                );
            }
        }
    }
}

/// A 1-pixel line drawn in 6-pixel dashes.
fn dashed(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), c: Rgb<u8>) {
    let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
    let steps = (len / 6.0).ceil().max(1.0) as usize;
    for k in (0..steps).step_by(2) {
        let t0 = k as f64 / steps as f64;
        let t1 = ((k + 1) as f64 / steps as f64).min(1.0);
        let at = |t: f64| (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        line(img, at(t0), at(t1), 1, c);
    }
}

/// The plot as an image: two panels side by side and the legend below them.
pub fn plot_image(curves: &[Curve]) -> RgbImage {
    let rows = curves.len().max(1) as u32;
    let height = PANEL_HEIGHT + 16 + rows * LEGEND_ROW + 10;
    let mut img = RgbImage::from_pixel(WIDTH, height, WHITE);
    let y_axis = LogAxis::around(
        curves
            .iter()
            .flat_map(|c| c.passes.iter())
            .flat_map(|p| [Some(p.error.rmse), p.estimate.map(|e| e.rmse)])
            .flatten(),
    );
    let panels = [
        Panel {
            title: "RMSE vs render time",
            x_label: "seconds",
            x_of: |p| p.seconds,
            estimates: false,
        },
        Panel {
            title: "RMSE vs spp (dashed: estimated)",
            x_label: "samples per pixel",
            x_of: |p| f64::from(p.spp),
            estimates: true,
        },
    ];
    for (i, panel) in panels.iter().enumerate() {
        draw_panel(
            &mut img,
            i as i32 * (WIDTH / 2) as i32,
            panel,
            curves,
            y_axis,
        );
    }
    // Legend: a swatch, the label and the fitted slopes.
    let mut y = (PANEL_HEIGHT + 16) as i32;
    let label_len = curves.iter().map(|c| c.label().len()).max().unwrap_or(0);
    for (i, c) in curves.iter().enumerate() {
        let color = curve_color(i);
        let x = 24;
        line(
            &mut img,
            (f64::from(x), f64::from(y + GLYPH / 2)),
            (f64::from(x + 40), f64::from(y + GLYPH / 2)),
            4,
            color,
        );
        let slope = |s: Option<f64>| s.map_or_else(|| "n/a".into(), |s| format!("{s:+.2}"));
        let ratio = c
            .estimate_ratio()
            .map_or_else(|| "n/a".into(), |r| format!("{r:.2}"));
        let label = format!(
            "{:<label_len$}   slope {} vs time, {} vs spp, estimate/true {ratio}",
            c.label(),
            slope(c.slope_time()),
            slope(c.slope_spp())
        );
        text(&mut img, x + 52, y, &label, BLACK);
        y += LEGEND_ROW as i32;
    }
    img
}

/// Writes the plot as a PNG (atomically).
pub fn write_plot(path: &Path, curves: &[Curve]) -> Result<()> {
    let img = plot_image(curves);
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|source| GlintError::Image {
            path: path.to_owned(),
            source,
        })?;
    write_atomically(path, bytes.get_ref())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(0.01), "0.01");
        assert_eq!(tick_label(1.0), "1");
        assert_eq!(tick_label(200.0), "200");
        assert_eq!(tick_label(1e-5), "1e-5");
        assert_eq!(tick_label(5e-4), "5e-4");
    }

    #[test]
    fn axis_spans_whole_decades() {
        let a = LogAxis::around([0.03, 0.2].into_iter());
        assert_eq!((a.lo, a.hi), (-2, 0));
        assert!((a.frac(0.1) - 0.5).abs() < 1e-12);
        let b = LogAxis::around([1.0].into_iter());
        assert_eq!((b.lo, b.hi), (0, 1));
    }

    #[test]
    fn text_draws_glyph_pixels() {
        let mut img = RgbImage::from_pixel(40, 20, WHITE);
        text(&mut img, 0, 0, "A", BLACK);
        assert!(img.pixels().any(|p| *p == BLACK));
        let mut up = RgbImage::from_pixel(20, 40, WHITE);
        text_up(&mut up, 0, 39, "A", BLACK);
        assert!(up.pixels().any(|p| *p == BLACK));
    }
}
