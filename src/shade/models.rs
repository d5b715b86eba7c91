//! The shading models of SPEC "Shading", evaluated for one light sample.
//!
//! Conventions: every direction is unit length and `n` faces the viewer; a
//! light with `n.l <= 0` (behind the surface as seen by the viewer)
//! contributes nothing in every model, shading off included. Outputs are
//! always finite: a NaN or infinite component (from bad input data) becomes
//! 0 rather than spreading through the image.

use glam::Vec3;

use super::gradient::Gradient;
use crate::scene::ShadingModel;

/// Everything one light sample needs to be shaded. All directions unit length; `n` faces the viewer.
#[derive(Clone, Copy, Debug)]
pub struct ShadingInput {
    /// Surface normal, facing the viewer.
    pub n: Vec3,
    /// Direction towards the light.
    pub l: Vec3,
    /// Direction towards the viewer (`-ray.dir`).
    pub v: Vec3,
    /// Colour of the light sample (after visibility).
    pub light_color: Vec3,
    /// Diffuse colour at the hit (texture sample or material `kd`).
    pub kd: Vec3,
    /// Specular colour.
    pub ks: Vec3,
    /// Specular exponent.
    pub shininess: f32,
}

/// Which model and gradients to use (borrowed from Settings).
#[derive(Clone, Copy, Debug)]
pub struct Shading<'a> {
    /// Shading on; off gives `light_color * kd`.
    pub enabled: bool,
    /// The model used when shading is on.
    pub model: ShadingModel,
    /// Gradient of the linear-gradient model.
    pub gradient: &'a Gradient,
    /// Gradient of the comparison model.
    pub comparison_gradient: &'a Gradient,
}

impl Shading<'_> {
    /// The light sample's contribution, exactly as SPEC "Shading".
    // Inlined into the light-sample loop: the call passed the whole input on the stack.
    #[inline(always)]
    pub fn shade(&self, input: &ShadingInput) -> Vec3 {
        if !lit(input) {
            return Vec3::ZERO;
        }
        if !self.enabled {
            return finite(input.light_color * input.kd);
        }
        match self.model {
            ShadingModel::Lambertian => lambertian(input),
            ShadingModel::Phong => phong(input),
            ShadingModel::BlinnPhong => blinn_phong(input),
            ShadingModel::LinearGradient => linear_gradient(input, self.gradient),
            ShadingModel::LinearGradientComparison => {
                linear_gradient_comparison(input, self.comparison_gradient)
            }
        }
    }
}

/// A shading model fixed at compile time ([`Shading::dispatch`]): code generic over it is
/// compiled once per model, without [`Shading::shade`]'s per-sample branches on the
/// settings. Each gives `Shading::shade`'s value for its settings, bit for bit.
pub trait Model: Copy + Sync {
    /// The light sample's contribution.
    fn shade(&self, input: &ShadingInput) -> Vec3;
}

/// [`lambertian`], the model of the render benchmark (and of Mitsuba's comparison).
#[derive(Clone, Copy, Debug)]
pub struct LambertianModel;

impl Model for LambertianModel {
    #[inline(always)]
    fn shade(&self, i: &ShadingInput) -> Vec3 {
        lambertian(i)
    }
}

/// The settings' model read per sample.
impl Model for Shading<'_> {
    #[inline(always)]
    fn shade(&self, i: &ShadingInput) -> Vec3 {
        Shading::shade(self, i)
    }
}

/// Code run with the settings' shading model as a type ([`Shading::dispatch`]).
pub trait WithModel {
    /// What the code returns.
    type Output;
    /// Runs the code with `model`.
    fn run<M: Model>(self, model: M) -> Self::Output;
}

impl Shading<'_> {
    /// Runs `code` with the [`Model`] these settings select: Lambertian as a type of its
    /// own, the others as the settings read per sample. (A copy per model was tried:
    /// Lambertian's pays, Phong's came out 16 instructions per ray slower than this.)
    pub fn dispatch<W: WithModel>(&self, code: W) -> W::Output {
        match (self.enabled, self.model) {
            (true, ShadingModel::Lambertian) => code.run(LambertianModel),
            _ => code.run(*self),
        }
    }
}

/// Whether the light is on the viewer's side of the surface (`n.l > 0`; NaN is not).
fn lit(i: &ShadingInput) -> bool {
    i.n.dot(i.l) > 0.0
}

/// Replaces non-finite components by 0.
fn finite(c: Vec3) -> Vec3 {
    Vec3::select(c.is_finite_mask(), c, Vec3::ZERO)
}

/// `max(x, 0)^shininess`, always finite.
///
/// `0^0` is 1 (as `powf` defines it), so shininess 0 makes the highlight a
/// constant `ks` over the lit side. A negative or NaN shininess is treated
/// as 0, since `0^negative` would be infinite.
fn specular_power(x: f32, shininess: f32) -> f32 {
    let base = if x > 0.0 { x.min(1.0) } else { 0.0 };
    let exponent = if shininess > 0.0 { shininess } else { 0.0 };
    base.powf(exponent)
}

/// The highlight `light * ks * specular_power(cos, shininess)`, `cos` asked for only when
/// it can matter.
///
/// `specular_power` is always in [0, 1] (never -0), and a signed zero times such a
/// number is that same signed zero: so when `light * ks` is all zeros (`ks = 0`, most
/// materials) it is the exact result, bit for bit, and the `powf` is skipped.
fn specular(i: &ShadingInput, cos: impl FnOnce() -> f32) -> Vec3 {
    let lk = i.light_color * i.ks;
    if lk == Vec3::ZERO {
        lk
    } else {
        lk * specular_power(cos(), i.shininess)
    }
}

/// The diffuse term `light * kd * max(n.l, 0)` with `kd` given.
fn diffuse(i: &ShadingInput, kd: Vec3) -> Vec3 {
    let cos_theta = i.n.dot(i.l).max(0.0);
    i.light_color * kd * cos_theta
}

/// Phong and Blinn-Phong before the NaN guard, so the comparison sees the raw values.
fn phong_raw(i: &ShadingInput) -> Vec3 {
    if !lit(i) {
        return Vec3::ZERO;
    }
    // reflect(-l, n) = -l - 2 (-l.n) n = 2 (n.l) n - l.
    let r = 2.0 * i.n.dot(i.l) * i.n - i.l;
    diffuse(i, i.kd) + specular(i, || r.dot(i.v))
}

/// Blinn-Phong before the NaN guard.
fn blinn_phong_raw(i: &ShadingInput) -> Vec3 {
    if !lit(i) {
        return Vec3::ZERO;
    }
    diffuse(i, i.kd)
        + specular(i, || {
            // l = -v has no half vector; normalize_or_zero gives n.h = 0 there.
            let h = (i.l + i.v).normalize_or_zero();
            i.n.dot(h)
        })
}

/// Lambertian: `light * kd * max(n.l, 0)`.
pub fn lambertian(i: &ShadingInput) -> Vec3 {
    if !lit(i) {
        return Vec3::ZERO;
    }
    finite(diffuse(i, i.kd))
}

/// Phong: lambertian + `light * ks * max(r.v, 0)^shininess`, `r = reflect(-l, n)`.
pub fn phong(i: &ShadingInput) -> Vec3 {
    finite(phong_raw(i))
}

/// Blinn-Phong: lambertian + `light * ks * max(n.h, 0)^shininess`, `h = normalize(l + v)`.
pub fn blinn_phong(i: &ShadingInput) -> Vec3 {
    finite(blinn_phong_raw(i))
}

/// Linear gradient: lambertian with `kd` replaced by `g.sample(n.l)`.
pub fn linear_gradient(i: &ShadingInput, g: &Gradient) -> Vec3 {
    if !lit(i) {
        return Vec3::ZERO;
    }
    let cos_theta = i.n.dot(i.l);
    finite(diffuse(i, g.sample(cos_theta)))
}

/// Comparison: `g.sample(t)` with `t = |phong - blinn_phong|`, negated unless `|phong| > |blinn_phong|`.
///
/// `|.|` is the vector length. The result is the gradient colour itself, not
/// scaled by the light, so equal models show the colour at `t = 0`.
pub fn linear_gradient_comparison(i: &ShadingInput, g: &Gradient) -> Vec3 {
    if !lit(i) {
        return Vec3::ZERO;
    }
    let t = comparison_t(finite(phong_raw(i)), finite(blinn_phong_raw(i)));
    finite(g.sample(t))
}

/// The signed difference of SPEC: `|p - b|` when `|p| > |b|`, else `-|p - b|`.
fn comparison_t(phong: Vec3, blinn_phong: Vec3) -> f32 {
    let d = (phong - blinn_phong).length();
    if phong.length() > blinn_phong.length() {
        d
    } else {
        -d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL_MODELS: [ShadingModel; 5] = [
        ShadingModel::Lambertian,
        ShadingModel::Phong,
        ShadingModel::BlinnPhong,
        ShadingModel::LinearGradient,
        ShadingModel::LinearGradientComparison,
    ];

    const EPS: f32 = 1e-5;

    /// Unit vector in the xz plane at `deg` degrees from +z (towards +x).
    fn at_angle(deg: f32) -> Vec3 {
        let r = deg.to_radians();
        Vec3::new(r.sin(), 0.0, r.cos())
    }

    fn input(l: Vec3, v: Vec3) -> ShadingInput {
        ShadingInput {
            n: Vec3::Z,
            l,
            v,
            light_color: Vec3::new(2.0, 1.0, 0.5),
            kd: Vec3::new(0.5, 0.25, 1.0),
            ks: Vec3::new(0.2, 0.4, 0.6),
            shininess: 8.0,
        }
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        a.abs_diff_eq(b, EPS)
    }

    fn shading<'a>(model: ShadingModel, g: &'a Gradient, c: &'a Gradient) -> Shading<'a> {
        Shading {
            enabled: true,
            model,
            gradient: g,
            comparison_gradient: c,
        }
    }

    #[test]
    fn lambertian_at_sixty_degrees() {
        let i = input(at_angle(60.0), Vec3::Z);
        assert!(close(lambertian(&i), 0.5 * i.kd * i.light_color));
        assert!(close(
            lambertian(&input(Vec3::Z, Vec3::Z)),
            i.kd * i.light_color
        ));
    }

    #[test]
    fn phong_mirror_direction_adds_full_ks() {
        // l at +30 deg reflects to -30 deg; v there makes r.v = 1.
        let i = input(at_angle(30.0), at_angle(-30.0));
        let cos = 30f32.to_radians().cos();
        let expected = i.light_color * i.kd * cos + i.light_color * i.ks;
        assert!(close(phong(&i), expected), "{}", phong(&i));
    }

    #[test]
    fn phong_exponent() {
        // l at 30 deg, v at 0 deg: r at -30 deg, r.v = cos 30.
        let i = input(at_angle(30.0), Vec3::Z);
        let cos = 30f32.to_radians().cos();
        let expected = i.light_color * i.kd * cos + i.light_color * i.ks * cos.powf(8.0);
        assert!(close(phong(&i), expected));
        // Away from the mirror direction the highlight vanishes.
        let far = input(at_angle(30.0), at_angle(80.0));
        let r_dot_v = 110f32.to_radians().cos().max(0.0);
        assert_eq!(r_dot_v, 0.0);
        assert!(close(phong(&far), far.light_color * far.kd * cos));
    }

    #[test]
    fn blinn_phong_half_vector_on_normal() {
        // l and v symmetric about n: h = n, n.h = 1.
        let i = input(at_angle(40.0), at_angle(-40.0));
        let cos = 40f32.to_radians().cos();
        let expected = i.light_color * i.kd * cos + i.light_color * i.ks;
        assert!(close(blinn_phong(&i), expected));
        // l at 60, v at 0: h at 30 deg.
        let j = input(at_angle(60.0), Vec3::Z);
        let expected =
            j.light_color * j.kd * 0.5 + j.light_color * j.ks * 30f32.to_radians().cos().powf(8.0);
        assert!(close(blinn_phong(&j), expected));
    }

    #[test]
    fn light_behind_gives_zero_everywhere() {
        let g = Gradient::default_shading();
        let c = Gradient::default_comparison();
        for l in [at_angle(120.0), at_angle(90.0), -Vec3::Z, Vec3::NAN] {
            let i = input(l, Vec3::Z);
            for model in ALL_MODELS {
                assert_eq!(
                    shading(model, &g, &c).shade(&i),
                    Vec3::ZERO,
                    "{model:?} {l}"
                );
            }
            let off = Shading {
                enabled: false,
                ..shading(ShadingModel::Phong, &g, &c)
            };
            assert_eq!(off.shade(&i), Vec3::ZERO);
        }
    }

    #[test]
    fn shading_off_is_light_times_kd() {
        let g = Gradient::default_shading();
        let off = Shading {
            enabled: false,
            ..shading(ShadingModel::Phong, &g, &g)
        };
        let i = input(at_angle(70.0), at_angle(-10.0));
        assert_eq!(off.shade(&i), i.light_color * i.kd);
    }

    #[test]
    fn shade_dispatches_to_model() {
        let g = Gradient::default_shading();
        let c = Gradient::default_comparison();
        let i = input(at_angle(30.0), at_angle(-20.0));
        assert_eq!(
            shading(ShadingModel::Lambertian, &g, &c).shade(&i),
            lambertian(&i)
        );
        assert_eq!(shading(ShadingModel::Phong, &g, &c).shade(&i), phong(&i));
        assert_eq!(
            shading(ShadingModel::BlinnPhong, &g, &c).shade(&i),
            blinn_phong(&i)
        );
        assert_eq!(
            shading(ShadingModel::LinearGradient, &g, &c).shade(&i),
            linear_gradient(&i, &g)
        );
        assert_eq!(
            shading(ShadingModel::LinearGradientComparison, &g, &c).shade(&i),
            linear_gradient_comparison(&i, &c)
        );
    }

    #[test]
    fn linear_gradient_replaces_kd() {
        // Gradient from black at 0 to (1, 2, 3) at 1: at cos = 0.5 it is (0.5, 1, 1.5).
        let g = Gradient::new(vec![(1.0, Vec3::new(1.0, 2.0, 3.0)), (0.0, Vec3::ZERO)]);
        let i = input(at_angle(60.0), Vec3::Z);
        let expected = i.light_color * Vec3::new(0.5, 1.0, 1.5) * 0.5;
        assert!(close(linear_gradient(&i, &g), expected));
    }

    #[test]
    fn comparison_t_sign_convention() {
        // Phong larger: positive t equal to the length of the difference (3, 4, 0) = 5.
        let t = comparison_t(Vec3::new(3.0, 4.0, 0.0), Vec3::ZERO);
        assert_eq!(t, 5.0);
        // Blinn-Phong larger: negative.
        assert_eq!(comparison_t(Vec3::ZERO, Vec3::new(0.0, 3.0, 4.0)), -5.0);
        // Equal lengths but different colours: not larger, so negative.
        assert_eq!(comparison_t(Vec3::X, Vec3::Y), -(2f32.sqrt()));
        assert_eq!(comparison_t(Vec3::ONE, Vec3::ONE), 0.0);
    }

    #[test]
    fn comparison_colours() {
        let c = Gradient::new(vec![
            (-1.0, Vec3::new(1.0, 0.0, 0.0)),
            (0.0, Vec3::ZERO),
            (1.0, Vec3::new(0.0, 0.0, 1.0)),
        ]);
        // l = v = n: both highlights are full, d = 0: the colour at t = 0.
        assert_eq!(
            linear_gradient_comparison(&input(Vec3::Z, Vec3::Z), &c),
            Vec3::ZERO
        );
        // l at 30 deg, v along n, shininess 1, white light 1, ks 1, kd 0:
        // Phong = cos 30, Blinn-Phong = cos 15 (h at 15 deg); t = -(cos 15 - cos 30) * sqrt 3.
        let mut i = input(at_angle(30.0), Vec3::Z);
        i.shininess = 1.0;
        i.kd = Vec3::ZERO;
        i.ks = Vec3::ONE;
        i.light_color = Vec3::ONE;
        let d = (15f32.to_radians().cos() - 30f32.to_radians().cos()) * 3f32.sqrt();
        let out = linear_gradient_comparison(&i, &c);
        assert!(close(out, Vec3::new(d, 0.0, 0.0)), "{out} vs {d}");
    }

    #[test]
    fn comparison_phong_larger_is_positive() {
        // Grazing light at 80 deg from n and a view 10 deg (in azimuth) off
        // the mirror direction: with a = n.l = n.v and c = l.v,
        // r.v = 2a^2 - c = 0.9855 exceeds n.h = 2a / sqrt(2 + 2c) = 0.898.
        let c = Gradient::new(vec![
            (-1.0, Vec3::new(1.0, 0.0, 0.0)),
            (0.0, Vec3::ZERO),
            (1.0, Vec3::new(0.0, 0.0, 1.0)),
        ]);
        let (sin, cos) = 80f32.to_radians().sin_cos();
        let psi = 170f32.to_radians();
        let mut i = input(
            Vec3::new(sin, 0.0, cos),
            Vec3::new(sin * psi.cos(), sin * psi.sin(), cos),
        );
        i.shininess = 1.0;
        i.kd = Vec3::ZERO;
        i.ks = Vec3::ONE;
        i.light_color = Vec3::ONE;
        let (a, cc) = (cos, i.l.dot(i.v));
        let r_dot_v = 2.0 * a * a - cc;
        let n_dot_h = 2.0 * a / (2.0 + 2.0 * cc).sqrt();
        assert!(r_dot_v > n_dot_h);
        assert!(close(phong(&i), Vec3::splat(r_dot_v)));
        assert!(close(blinn_phong(&i), Vec3::splat(n_dot_h)));
        let t = (r_dot_v - n_dot_h) * 3f32.sqrt();
        let out = linear_gradient_comparison(&i, &c);
        assert!(close(out, Vec3::new(0.0, 0.0, t)), "{out} vs {t}");
    }

    #[test]
    fn zero_ks_skips_the_power_bit_for_bit() {
        // The formulas as written before the `ks = 0` shortcut, every bit compared:
        // signed zeros, negative and infinite lights, NaN and infinite shininess.
        let reference_phong = |i: &ShadingInput| {
            let r = 2.0 * i.n.dot(i.l) * i.n - i.l;
            diffuse(i, i.kd) + i.light_color * i.ks * specular_power(r.dot(i.v), i.shininess)
        };
        let reference_blinn = |i: &ShadingInput| {
            let h = (i.l + i.v).normalize_or_zero();
            diffuse(i, i.kd) + i.light_color * i.ks * specular_power(i.n.dot(h), i.shininess)
        };
        let bits = |c: Vec3| c.to_array().map(f32::to_bits);
        let lights = [
            Vec3::new(2.0, 1.0, 0.5),
            Vec3::new(-1.0, 0.0, -0.0),
            Vec3::new(f32::INFINITY, 1.0, -0.0),
        ];
        let kss = [
            Vec3::ZERO,
            Vec3::new(-0.0, 0.0, -0.0),
            Vec3::new(0.0, 0.3, 0.0),
            Vec3::new(0.2, 0.4, 0.6),
        ];
        let kds = [Vec3::new(0.5, 0.25, 1.0), Vec3::new(-0.0, 0.0, 0.0)];
        for light_color in lights {
            for ks in kss {
                for kd in kds {
                    for shininess in [8.0, 0.0, f32::NAN, f32::INFINITY] {
                        for (l, v) in [
                            (at_angle(30.0), at_angle(-30.0)),
                            (at_angle(10.0), at_angle(70.0)),
                        ] {
                            let i = ShadingInput {
                                light_color,
                                ks,
                                kd,
                                shininess,
                                ..input(l, v)
                            };
                            assert_eq!(bits(phong_raw(&i)), bits(reference_phong(&i)), "{i:?}");
                            assert_eq!(
                                bits(blinn_phong_raw(&i)),
                                bits(reference_blinn(&i)),
                                "{i:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn edge_cases_are_finite() {
        // Shininess 0 with r.v <= 0: 0^0 = 1, a constant ks highlight.
        let mut i = input(at_angle(30.0), at_angle(80.0));
        i.shininess = 0.0;
        let cos = 30f32.to_radians().cos();
        assert!(close(phong(&i), i.light_color * (i.kd * cos + i.ks)));
        // Negative shininess would be 0^-1 = inf; treated as 0.
        i.shininess = -2.0;
        assert!(phong(&i).is_finite());
        assert!(blinn_phong(&i).is_finite());
        i.shininess = f32::NAN;
        assert!(phong(&i).is_finite());
        // NaN colours or view give finite results.
        let mut j = input(at_angle(30.0), Vec3::NAN);
        j.light_color = Vec3::new(f32::NAN, 1.0, f32::INFINITY);
        for model in [phong(&j), blinn_phong(&j), lambertian(&j)] {
            assert!(model.is_finite(), "{model}");
        }
        // l = -v cannot happen when n faces the viewer, but must not be NaN.
        let k = input(at_angle(10.0), -at_angle(10.0));
        assert!(blinn_phong(&k).is_finite());
    }

    #[test]
    fn dispatched_models_give_the_settings_shading_bit_for_bit() {
        /// Shades one input with the dispatched model.
        struct Probe(ShadingInput);
        impl WithModel for Probe {
            type Output = Vec3;
            fn run<M: Model>(self, model: M) -> Vec3 {
                model.shade(&self.0)
            }
        }
        let (g, c) = (Gradient::default_shading(), Gradient::default_comparison());
        let mut inputs = vec![
            input(at_angle(30.0), at_angle(-30.0)),
            input(at_angle(30.0), Vec3::Z),
            input(at_angle(60.0), at_angle(10.0)),
            input(at_angle(100.0), Vec3::Z),
        ];
        let mut bad = input(at_angle(20.0), Vec3::Z);
        bad.light_color = Vec3::new(f32::NAN, f32::INFINITY, 1.0);
        inputs.push(bad);
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for enabled in [true, false] {
            for model in ALL_MODELS {
                let s = Shading {
                    enabled,
                    ..shading(model, &g, &c)
                };
                for i in &inputs {
                    assert_eq!(
                        bits(s.dispatch(Probe(*i))),
                        bits(s.shade(i)),
                        "{model:?} enabled {enabled}"
                    );
                }
            }
        }
    }
}
