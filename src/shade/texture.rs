//! Texture lookups (SPEC "Textures"): wrap modes, nearest and bilinear filtering. The
//! texture data and its decoding are in `scene::texture`.

use glam::{Vec2, Vec3};

pub use crate::scene::texture::{Texture, WrapMode};

/// Brings a coordinate into one period of its wrap mode before it is scaled to texels.
///
/// Reducing first keeps all the precision `f32` has in the fractional part
/// (for `u = 1e6 + 0.25` the lookup still lands a quarter of the way in);
/// scaling first would multiply the rounding error by the texture size.
/// Non-finite coordinates become 0.
fn reduce(t: f32, mode: WrapMode) -> f32 {
    if !t.is_finite() {
        return 0.0;
    }
    match mode {
        // Anything past one texel outside clamps to the edge anyway.
        WrapMode::Clamp => t.clamp(-1.0, 2.0),
        // Both subtractions are exact in f32.
        WrapMode::Repeat => t - t.floor(),
        WrapMode::MirroredRepeat => t - 2.0 * (t * 0.5).floor(),
    }
}

/// Applies the wrap mode to a texel index along an axis of `size` texels.
fn wrap_index(i: i64, size: u32, mode: WrapMode) -> u32 {
    let n = i64::from(size.max(1));
    let w = match mode {
        WrapMode::Clamp => i.clamp(0, n - 1),
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
    };
    w as u32
}

// Lookups are shading, so they live here, while the data type lives in scene below shade.
impl Texture {
    /// Whether the texture has no texels to read (a lookup then gives black).
    fn is_empty(&self) -> bool {
        self.width == 0
            || self.height == 0
            || self.texels.len() < self.width as usize * self.height as usize
    }

    /// The texel at column i, row j (row 0 at the top).
    ///
    /// Out-of-range indices (and an empty texture) give black.
    pub fn texel(&self, i: u32, j: u32) -> Vec3 {
        if self.is_empty() || i >= self.width || j >= self.height {
            return Vec3::ZERO;
        }
        let index = j as usize * self.width as usize + i as usize;
        self.texels.get(index).copied().unwrap_or(Vec3::ZERO)
    }

    /// Continuous texel coordinates of `uv`: x from the left edge, y from the *bottom* edge.
    ///
    /// Working from the bottom keeps the cells half-open in `v` like in `u`:
    /// `v = 0` is in the bottom row and `v = 1` starts the next tile, as for
    /// `u`, whatever the wrap mode. SPEC's `row = (1 - v) * height` agrees
    /// everywhere except exactly on a row boundary.
    fn scaled(&self, uv: Vec2, wrap: [WrapMode; 2]) -> (f32, f32) {
        let x = reduce(uv.x, wrap[0]) * self.width as f32;
        let y = reduce(uv.y, wrap[1]) * self.height as f32;
        (x, y)
    }

    /// Texel (column, row) of the unwrapped indices `i` (from the left) and `b` (from the bottom).
    fn wrapped(&self, i: i64, b: i64, wrap: [WrapMode; 2]) -> (u32, u32) {
        let column = wrap_index(i, self.width, wrap[0]);
        let from_bottom = wrap_index(b, self.height, wrap[1]);
        (column, self.height.max(1) - 1 - from_bottom)
    }

    /// The texel coordinates (column, row) a nearest lookup at `uv` reads, for the visual debug.
    ///
    /// A NaN or infinite `uv` reads texel (0, 0).
    pub fn nearest_texel(&self, uv: Vec2, wrap: [WrapMode; 2]) -> (u32, u32) {
        if self.is_empty() || !uv.is_finite() {
            return (0, 0);
        }
        let (x, y) = self.scaled(uv, wrap);
        // `as` saturates, so even a huge clamp-mode coordinate stays an index.
        self.wrapped(x.floor() as i64, y.floor() as i64, wrap)
    }

    /// The four texels (column, row) a bilinear lookup at `uv` reads and their weights (summing to 1), for the visual debug.
    ///
    /// Order: lower-left, lower-right, upper-left, upper-right around `uv`.
    /// A NaN or infinite `uv` reads texel (0, 0) with all the weight.
    pub fn bilinear_texels(&self, uv: Vec2, wrap: [WrapMode; 2]) -> [((u32, u32), f32); 4] {
        if self.is_empty() || !uv.is_finite() {
            return [((0, 0), 1.0), ((0, 0), 0.0), ((0, 0), 0.0), ((0, 0), 0.0)];
        }
        let (x, y) = self.scaled(uv, wrap);
        // Texel centres sit at half-integers; shift so they are at integers.
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i, b) = (x0 as i64, y0 as i64);
        [
            (self.wrapped(i, b, wrap), (1.0 - fx) * (1.0 - fy)),
            (self.wrapped(i + 1, b, wrap), fx * (1.0 - fy)),
            (self.wrapped(i, b + 1, wrap), (1.0 - fx) * fy),
            (self.wrapped(i + 1, b + 1, wrap), fx * fy),
        ]
    }

    /// Nearest lookup at texture coordinate uv (v = 0 is the bottom row) with per-axis wrap.
    pub fn sample_nearest(&self, uv: Vec2, wrap: [WrapMode; 2]) -> Vec3 {
        let (i, j) = self.nearest_texel(uv, wrap);
        self.texel(i, j)
    }

    /// Bilinear lookup: the four texels around uv weighted by distance to their centres.
    pub fn sample_bilinear(&self, uv: Vec2, wrap: [WrapMode; 2]) -> Vec3 {
        self.bilinear_texels(uv, wrap)
            .iter()
            .map(|&((i, j), w)| w * self.texel(i, j))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MODES: [WrapMode; 3] = [WrapMode::Clamp, WrapMode::Repeat, WrapMode::MirroredRepeat];

    /// A `w x h` texture whose texel (i, j) is (i, j, 1 + i + w j): all distinct.
    fn grid(w: u32, h: u32) -> Texture {
        let mut texels = Vec::new();
        for j in 0..h {
            for i in 0..w {
                texels.push(Vec3::new(i as f32, j as f32, (1 + i + w * j) as f32));
            }
        }
        Texture {
            width: w,
            height: h,
            texels,
        }
    }

    /// uv of the centre of texel (i, j).
    fn centre(t: &Texture, i: u32, j: u32) -> Vec2 {
        Vec2::new(
            (i as f32 + 0.5) / t.width as f32,
            1.0 - (j as f32 + 0.5) / t.height as f32,
        )
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        a.abs_diff_eq(b, 1e-5)
    }

    #[test]
    fn texel_indexing_and_out_of_range() {
        let t = grid(3, 2);
        assert_eq!(t.texel(0, 0), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(t.texel(2, 1), Vec3::new(2.0, 1.0, 6.0));
        assert_eq!(t.texel(3, 0), Vec3::ZERO);
        assert_eq!(t.texel(0, 2), Vec3::ZERO);
    }

    #[test]
    fn centres_read_exact_texel() {
        for t in [grid(2, 2), grid(3, 2), grid(1, 1), grid(5, 1)] {
            for j in 0..t.height {
                for i in 0..t.width {
                    let uv = centre(&t, i, j);
                    for m in MODES {
                        let wrap = [m, m];
                        assert_eq!(t.nearest_texel(uv, wrap), (i, j));
                        assert_eq!(t.sample_nearest(uv, wrap), t.texel(i, j));
                        let b = t.sample_bilinear(uv, wrap);
                        assert!(close(b, t.texel(i, j)), "{m:?} ({i},{j}) {b}");
                    }
                }
            }
        }
    }

    #[test]
    fn row_zero_is_top_v_zero_is_bottom() {
        let t = grid(3, 2);
        let c = [WrapMode::Clamp; 2];
        assert_eq!(t.nearest_texel(Vec2::new(0.1, 0.9), c), (0, 0));
        assert_eq!(t.nearest_texel(Vec2::new(0.1, 0.1), c), (0, 1));
        // v = 0 and u = 0 are the bottom-left texel in every mode.
        for m in MODES {
            assert_eq!(t.nearest_texel(Vec2::ZERO, [m, m]), (0, 1), "{m:?}");
        }
        // v = 1, u = 1 are the top-right texel when clamped.
        assert_eq!(t.nearest_texel(Vec2::ONE, c), (2, 0));
    }

    #[test]
    fn bilinear_halfway_is_average() {
        let t = grid(3, 2);
        let c = [WrapMode::Clamp; 2];
        // Between the centres of (0, 0) and (1, 0): u = 1/3, top row centre v = 0.75.
        let b = t.sample_bilinear(Vec2::new(1.0 / 3.0, 0.75), c);
        assert!(close(b, (t.texel(0, 0) + t.texel(1, 0)) / 2.0), "{b}");
        // Between rows: v = 0.5 at the centre column.
        let b = t.sample_bilinear(Vec2::new(0.5, 0.5), c);
        assert!(close(b, (t.texel(1, 0) + t.texel(1, 1)) / 2.0), "{b}");
        // 2x2 centre: the mean of all four.
        let q = grid(2, 2);
        let b = q.sample_bilinear(Vec2::splat(0.5), c);
        let mean = (q.texel(0, 0) + q.texel(1, 0) + q.texel(0, 1) + q.texel(1, 1)) / 4.0;
        assert!(close(b, mean), "{b}");
        // A quarter of the way: weights 3/4 and 1/4.
        let b = t.sample_bilinear(Vec2::new(0.25, 0.75), c);
        let expected = 0.75 * t.texel(0, 0) + 0.25 * t.texel(1, 0);
        assert!(close(b, expected), "{b}");
    }

    #[test]
    fn bilinear_at_edges_per_mode() {
        let t = grid(3, 2);
        let left = Vec2::new(0.0, 0.75); // left edge, top row centre
        let clamp = t.sample_bilinear(left, [WrapMode::Clamp; 2]);
        assert!(close(clamp, t.texel(0, 0)), "{clamp}");
        let repeat = t.sample_bilinear(left, [WrapMode::Repeat; 2]);
        assert!(
            close(repeat, (t.texel(0, 0) + t.texel(2, 0)) / 2.0),
            "{repeat}"
        );
        let mirror = t.sample_bilinear(left, [WrapMode::MirroredRepeat; 2]);
        assert!(close(mirror, t.texel(0, 0)), "{mirror}");
        // Top edge, middle column: clamp keeps row 0, repeat mixes with the bottom row.
        let top = Vec2::new(0.5, 1.0);
        assert!(close(
            t.sample_bilinear(top, [WrapMode::Clamp; 2]),
            t.texel(1, 0)
        ));
        let r = t.sample_bilinear(top, [WrapMode::Repeat; 2]);
        assert!(close(r, (t.texel(1, 0) + t.texel(1, 1)) / 2.0), "{r}");
    }

    #[test]
    fn nearest_outside_unit_square_per_mode() {
        let t = grid(3, 2);
        let row = 0.75; // top row
        let cases = [
            // (u, clamp column, repeat column, mirrored column)
            (1.0 + 0.5 / 3.0, 2, 0, 2),
            (-0.5 / 3.0, 0, 2, 0),
            (1.5, 2, 1, 1),
            (1.9, 2, 2, 0),
            (-1.9, 0, 0, 0),
            (2.1, 2, 0, 0),
        ];
        for (u, c, r, m) in cases {
            let uv = Vec2::new(u, row);
            assert_eq!(
                t.nearest_texel(uv, [WrapMode::Clamp; 2]),
                (c, 0),
                "clamp {u}"
            );
            assert_eq!(
                t.nearest_texel(uv, [WrapMode::Repeat; 2]),
                (r, 0),
                "repeat {u}"
            );
            let mm = [WrapMode::MirroredRepeat; 2];
            assert_eq!(t.nearest_texel(uv, mm), (m, 0), "mirror {u}");
        }
        // Along v: 1.25 is the bottom row repeated, the top row clamped or mirrored.
        let uv = Vec2::new(0.5, 1.25);
        assert_eq!(t.nearest_texel(uv, [WrapMode::Repeat; 2]), (1, 1));
        assert_eq!(t.nearest_texel(uv, [WrapMode::Clamp; 2]), (1, 0));
        assert_eq!(t.nearest_texel(uv, [WrapMode::MirroredRepeat; 2]), (1, 0));
        // Per-axis modes are independent.
        let mixed = [WrapMode::Repeat, WrapMode::Clamp];
        assert_eq!(t.nearest_texel(Vec2::new(1.5, -3.0), mixed), (1, 1));
    }

    #[test]
    fn huge_coordinates_keep_precision() {
        let t = grid(2, 2);
        let r = [WrapMode::Repeat; 2];
        let m = [WrapMode::MirroredRepeat; 2];
        let c = [WrapMode::Clamp; 2];
        // 1e6 and 1e6 + 0.25 are exact in f32.
        assert_eq!(t.nearest_texel(Vec2::new(1e6 + 0.25, 0.75), r), (0, 0));
        assert_eq!(t.nearest_texel(Vec2::new(1e6 + 0.75, 0.75), r), (1, 0));
        assert_eq!(t.nearest_texel(Vec2::new(-1e6 + 0.25, 0.75), r), (0, 0));
        assert_eq!(t.nearest_texel(Vec2::new(0.25, -1e6 + 0.25), r), (0, 1));
        // 1e6 is an even number of tiles: mirrored like the first tile, then reflected.
        assert_eq!(t.nearest_texel(Vec2::new(1e6 + 0.25, 0.75), m), (0, 0));
        assert_eq!(t.nearest_texel(Vec2::new(1e6 + 1.25, 0.75), m), (1, 0));
        assert_eq!(t.nearest_texel(Vec2::new(1e6, -1e6), c), (1, 1));
        assert_eq!(t.nearest_texel(Vec2::new(-1e6, 1e6), c), (0, 0));
        let b = t.sample_bilinear(Vec2::new(1e6 + 0.25, 0.75), r);
        assert!(close(b, t.texel(0, 0)), "{b}");
    }

    #[test]
    fn extreme_and_nan_coordinates_do_not_panic() {
        let t = grid(3, 2);
        let values = [
            0.0,
            1.0,
            -1e6,
            1e6,
            1e30,
            -1e30,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -1e-9,
            1.0 - 1e-8,
        ];
        for m0 in MODES {
            for m1 in MODES {
                for &u in &values {
                    for &v in &values {
                        let uv = Vec2::new(u, v);
                        let (i, j) = t.nearest_texel(uv, [m0, m1]);
                        assert!(i < 3 && j < 2, "{uv} {m0:?} {m1:?}");
                        let texels = t.bilinear_texels(uv, [m0, m1]);
                        let sum: f32 = texels.iter().map(|x| x.1).sum();
                        assert!((sum - 1.0).abs() < 1e-5, "{uv}: {sum}");
                        for ((i, j), w) in texels {
                            assert!(i < 3 && j < 2 && (0.0..=1.0).contains(&w));
                        }
                        assert!(t.sample_bilinear(uv, [m0, m1]).is_finite());
                    }
                }
            }
        }
        let nan = Vec2::new(f32::NAN, 0.3);
        assert_eq!(t.nearest_texel(nan, [WrapMode::Repeat; 2]), (0, 0));
        assert_eq!(t.sample_bilinear(nan, [WrapMode::Repeat; 2]), t.texel(0, 0));
    }

    #[test]
    fn one_by_one_and_non_square() {
        let one = Texture {
            width: 1,
            height: 1,
            texels: vec![Vec3::new(0.2, 0.4, 0.6)],
        };
        for m in MODES {
            for uv in [
                Vec2::ZERO,
                Vec2::ONE,
                Vec2::new(-3.7, 12.2),
                Vec2::splat(0.5),
            ] {
                assert_eq!(one.sample_nearest(uv, [m, m]), one.texels[0]);
                assert!(close(one.sample_bilinear(uv, [m, m]), one.texels[0]));
            }
        }
        // 1000 x 1: u picks the column, any v the single row.
        let wide = grid(1000, 1);
        let uv = Vec2::new(0.5005, 0.1);
        assert_eq!(wide.nearest_texel(uv, [WrapMode::Clamp; 2]), (500, 0));
        let b = wide.sample_bilinear(Vec2::new(0.5, 0.9), [WrapMode::Clamp; 2]);
        assert!(
            close(b, (wide.texel(499, 0) + wide.texel(500, 0)) / 2.0),
            "{b}"
        );
        let tall = grid(1, 1000);
        assert_eq!(
            tall.nearest_texel(Vec2::new(0.3, 0.0), [WrapMode::Repeat; 2]),
            (0, 999)
        );
    }

    #[test]
    fn weights_sum_to_one_and_match_sample() {
        let t = grid(3, 2);
        let s = crate::sampling::Sampler::new(8);
        for k in 0..2000 {
            let uv = s.get2(k, 0, 0) * 6.0 - Vec2::splat(3.0);
            for m in MODES {
                let texels = t.bilinear_texels(uv, [m, m]);
                let sum: f32 = texels.iter().map(|x| x.1).sum();
                assert!((sum - 1.0).abs() < 1e-5);
                let manual: Vec3 = texels.iter().map(|&((i, j), w)| w * t.texel(i, j)).sum();
                assert_eq!(t.sample_bilinear(uv, [m, m]), manual);
            }
        }
    }

    #[test]
    fn empty_texture_is_black() {
        let t = Texture {
            width: 0,
            height: 0,
            texels: Vec::new(),
        };
        assert_eq!(
            t.sample_nearest(Vec2::splat(0.5), [WrapMode::Repeat; 2]),
            Vec3::ZERO
        );
        assert_eq!(
            t.sample_bilinear(Vec2::splat(0.5), [WrapMode::Clamp; 2]),
            Vec3::ZERO
        );
    }
}
