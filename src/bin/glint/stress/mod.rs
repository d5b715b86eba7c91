//! `glint stress`: numerical stability on stiff and extreme cases.
//!
//! Each case builds its scene procedurally (RON text through [`parse_scene`] and
//! [`Renderer::from_scene`], or a `World` / [`SceneGeometry`] built directly), renders
//! or traces it, and returns measured [`Row`]s: what was measured, the value, the bound
//! it must not exceed, and whether it passed. The same cases run as tests
//! (`tests/stress.rs`) with the small [`Budget::quick`]; the command line uses
//! [`Budget::full`] (millions of rays). See `docs/stress.md` for the table and for how
//! each failure mode is prevented.
//!
//! [`SceneGeometry`]: glint::trace::geometry::SceneGeometry

use std::fmt::Write as _;
use std::path::Path;

use glam::Vec3;

use glint::Result;
use glint::film::Film;
use glint::render::Renderer;
use glint::scene::parse_scene;
use glint::stats::RenderStats;

use crate::cli::StressArgs;
use crate::{CliError, CliResult, set_threads};

mod coincident;
mod deep_chains;
mod geometry;
mod lights;
mod reference;
mod scale;
mod scenes;
mod spheres;
mod textures;
mod validation;

/// One measurement of a case.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The case (e.g. `scale 1e-4`).
    pub case: String,
    /// What is measured (e.g. `acne pixels`).
    pub measure: String,
    /// The measured value.
    pub value: f64,
    /// The bound: the value must not exceed it (or must equal it, see `measure`).
    pub bound: f64,
    /// Whether the value is within the bound (a NaN value never passes).
    pub pass: bool,
}

impl Row {
    /// The row every rendered case has: no NaN or infinite pixel or sample.
    pub fn finite(case: impl Into<String>, nonfinite: f64) -> Self {
        Self::at_most(case, "non-finite pixels and samples", nonfinite, 0.0)
    }

    /// A row that passes when `value <= bound`.
    pub fn at_most(
        case: impl Into<String>,
        measure: impl Into<String>,
        value: f64,
        bound: f64,
    ) -> Row {
        Row {
            case: case.into(),
            measure: measure.into(),
            value,
            bound,
            pass: value <= bound,
        }
    }

    /// A row that passes when `value == expected` (a count that must match exactly).
    pub fn exactly(
        case: impl Into<String>,
        measure: impl Into<String>,
        value: f64,
        expected: f64,
    ) -> Row {
        Row {
            case: case.into(),
            measure: format!("{} (= bound)", measure.into()),
            value,
            bound: expected,
            pass: value == expected,
        }
    }

    /// A failing row for a case that could not run.
    pub fn error(case: impl Into<String>, message: impl std::fmt::Display) -> Row {
        Row {
            case: case.into(),
            measure: format!("error: {message}"),
            value: f64::NAN,
            bound: 0.0,
            pass: false,
        }
    }
}

/// How much work each case does: small for the test suite, large for the command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// Image width of rendered cases (height is 3/4 of it).
    pub width: u32,
    /// Rays per mesh in the watertightness case (a tenth per kind in the traversal case).
    pub rays: usize,
    /// Use the largest sample counts (shadow_samples 4096 on a full image).
    pub full: bool,
}

impl Budget {
    /// Small images and ray counts: the whole suite runs in seconds.
    pub fn quick() -> Budget {
        Budget {
            width: 48,
            rays: 60_000,
            full: false,
        }
    }

    /// The command's default: larger images and millions of rays.
    pub fn full() -> Budget {
        Budget {
            width: 160,
            rays: 1_000_000,
            full: true,
        }
    }

    /// Image height for `width`.
    pub fn height(&self) -> u32 {
        self.width * 3 / 4
    }
}

/// A stress case: a name and the function that measures it.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// Short name, also the `--case` filter and the test name.
    pub name: &'static str,
    /// Builds, renders or traces, and measures.
    pub run: fn(&Budget) -> Vec<Row>,
}

/// Every case, in the order of issue 6.
pub fn cases() -> Vec<Case> {
    vec![
        // One lit scene scaled by 1e-4 .. 1e6.
        Case {
            name: "scale",
            run: scale::scale,
        },
        // The same scene translated by 1e3 .. 1e6.
        Case {
            name: "far",
            run: scale::far,
        },
        // Rays at shared edges and vertices of closed meshes and a fan.
        Case {
            name: "watertight",
            run: geometry::watertight,
        },
        // Axis-aligned and grazing rays, BVH against brute force.
        Case {
            name: "axis_grazing",
            run: geometry::axis_grazing,
        },
        // Zero-area, collinear, duplicate-vertex and needle triangles.
        Case {
            name: "degenerate",
            run: geometry::degenerate,
        },
        // Surfaces 1e-3, 1e-5 and 0 apart, a surface at a light.
        Case {
            name: "coincident",
            run: coincident::coincident,
        },
        // 100 stacked transparent quads, facing mirrors to depth 64.
        Case {
            name: "deep_chains",
            run: deep_chains::deep_chains,
        },
        // Radius 1e-6 and 1e6, camera inside, tangent rays.
        Case {
            name: "spheres",
            run: spheres::spheres,
        },
        // Degenerate area lights, colour 1e6, light inside geometry, 1..4096 samples.
        Case {
            name: "lights",
            run: lights::lights,
        },
        // 1x1 and 4096x1 textures, texture coordinates of +-1e6.
        Case {
            name: "textures",
            run: textures::textures,
        },
        // Every non-finite or out-of-range input is rejected at load.
        Case {
            name: "validation",
            run: validation::validation,
        },
    ]
}

/// Runs one case, turning a panic into a failing row (a panic is a failure too).
pub fn run_case(case: &Case, budget: &Budget) -> Vec<Row> {
    match std::panic::catch_unwind(|| (case.run)(budget)) {
        Ok(rows) if rows.is_empty() => vec![Row::error(case.name, "no measurement")],
        Ok(rows) => rows,
        Err(p) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "panic".into());
            vec![Row::error(case.name, format!("panicked: {msg}"))]
        }
    }
}

fn fmt_value(v: f64) -> String {
    if v.is_nan() {
        "-".into()
    } else if v == v.trunc() && v.abs() < 1e9 {
        format!("{v}")
    } else {
        format!("{v:.3e}")
    }
}

/// The rows as a markdown table.
pub fn table(rows: &[Row]) -> String {
    let mut s =
        String::from("| case | measure | value | bound | result |\n|---|---|---:|---:|---|\n");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} |",
            r.case,
            r.measure,
            fmt_value(r.value),
            fmt_value(r.bound),
            if r.pass { "pass" } else { "**FAIL**" }
        );
    }
    s
}

/// The rows as CSV (`case,measure,value,bound,pass`).
pub fn csv(rows: &[Row]) -> String {
    let quote = |s: &str| format!("\"{}\"", s.replace('"', "\"\""));
    let mut s = String::from("case,measure,value,bound,pass\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{:e},{:e},{}",
            quote(&r.case),
            quote(&r.measure),
            r.value,
            r.bound,
            r.pass
        );
    }
    s
}

/// The `glint stress` command: runs the cases whose name contains `--case` (all when
/// absent), prints the table, writes the CSV; fails when any row fails.
pub fn run(args: &StressArgs) -> CliResult<()> {
    set_threads(args.threads)?;
    let budget = if args.quick {
        Budget::quick()
    } else {
        Budget::full()
    };
    let only = args.case.as_deref();
    let selected: Vec<Case> = cases()
        .into_iter()
        .filter(|c| only.is_none_or(|o| c.name.contains(o)))
        .collect();
    if selected.is_empty() {
        let names: Vec<&str> = cases().iter().map(|c| c.name).collect();
        return Err(CliError::Flag(format!(
            "--case {}: no such case (cases: {})",
            only.unwrap_or_default(),
            names.join(", ")
        )));
    }
    let mut rows = Vec::new();
    for case in &selected {
        let start = std::time::Instant::now();
        let r = run_case(case, &budget);
        let failed = r.iter().filter(|r| !r.pass).count();
        say!(
            "{:<12} {:>6.2} s  {}",
            case.name,
            start.elapsed().as_secs_f64(),
            if failed == 0 {
                "pass".to_string()
            } else {
                format!("{failed} FAILED")
            }
        );
        rows.extend(r);
    }
    crate::print_stdout(&table(&rows));
    if let Some(path) = &args.csv {
        glint::film::write_atomically(path, csv(&rows).as_bytes())?;
    }
    if rows.iter().all(|r| r.pass) {
        Ok(())
    } else {
        Err(CliError::Failed(
            "some stress cases failed (see the table)".into(),
        ))
    }
}

// ---------------------------------------------------------------------------------------
// Helpers shared by the cases.

/// A finished render: the image, its size and the run's statistics.
pub struct Rendered {
    /// Mean radiance per pixel, row-major.
    pub image: Vec<Vec3>,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Statistics (rays, dropped non-finite samples).
    pub stats: RenderStats,
}

impl Rendered {
    /// Pixels with a NaN or infinite component, plus samples the film dropped as non-finite.
    pub fn nonfinite(&self) -> f64 {
        (self.image.iter().filter(|p| !p.is_finite()).count() as u64 + self.stats.nonfinite_samples)
            as f64
    }

    /// Largest per-component absolute difference to `other` (infinite if sizes differ).
    pub fn max_diff(&self, other: &Rendered) -> f64 {
        if self.image.len() != other.image.len() {
            return f64::INFINITY;
        }
        self.image
            .iter()
            .zip(&other.image)
            .map(|(a, b)| (*a - *b).abs().max_element() as f64)
            .fold(0.0, f64::max)
    }

    /// Mean per-pixel largest-component absolute difference to `other`.
    pub fn mean_diff(&self, other: &Rendered) -> f64 {
        if self.image.len() != other.image.len() {
            return f64::INFINITY;
        }
        let sum: f64 = self
            .image
            .iter()
            .zip(&other.image)
            .map(|(a, b)| (*a - *b).abs().max_element() as f64)
            .sum();
        sum / self.image.len().max(1) as f64
    }

    /// Largest per-component absolute difference to the constant `expected`.
    pub fn max_diff_to(&self, expected: Vec3) -> f64 {
        self.image
            .iter()
            .map(|p| (*p - expected).abs().max_element() as f64)
            .fold(
                0.0,
                |a: f64, b| if b.is_nan() { f64::INFINITY } else { a.max(b) },
            )
    }
}

/// Renders a renderer to completion.
pub fn render(mut r: Renderer) -> Result<Rendered> {
    r.render(None, &mut |_| {})?;
    let film: &Film = r.film();
    Ok(Rendered {
        image: film.image(),
        width: film.width,
        height: film.height,
        stats: r.stats().clone(),
    })
}

/// Parses RON scene text and renders it.
pub fn render_ron(text: &str) -> Result<Rendered> {
    let path = Path::new("<stress>.ron");
    let file = parse_scene(text, path)?;
    render(Renderer::from_scene(&file, path)?)
}

/// Formats a vector as a RON tuple with enough digits to round-trip f32.
pub fn v3(v: Vec3) -> String {
    format!("({:?}, {:?}, {:?})", v.x, v.y, v.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_has_a_test() {
        let source = include_str!("../../../../tests/stress.rs");
        for c in cases() {
            assert!(
                source.contains(&format!("check(\"{}\")", c.name)),
                "no test for case {}",
                c.name
            );
        }
    }

    #[test]
    fn rows_fail_outside_their_bound_and_on_nan() {
        assert!(Row::at_most("c", "m", 0.0, 0.0).pass);
        assert!(!Row::at_most("c", "m", 1.0, 0.0).pass);
        assert!(!Row::at_most("c", "m", f64::NAN, 0.0).pass);
        assert!(!Row::exactly("c", "m", 2.0, 3.0).pass);
        let rows = [Row::at_most("a \"b\"", "m", 1.5, 2.0)];
        assert_eq!(
            csv(&rows),
            "case,measure,value,bound,pass\n\"a \"\"b\"\"\",\"m\",1.5e0,2e0,true\n"
        );
        assert!(table(&rows).contains("| a \"b\" | m | 1.500e0 | 2 | pass |"));
    }
}
