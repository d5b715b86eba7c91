//! Cases 1 and 2: one lit scene (a floor under a point light, a sphere, a closed mesh,
//! an area light) scaled by 1e-4 .. 1e6 and translated by 1e3 .. 1e6.
//!
//! Every coordinate of the unit scene is a multiple of 1/16, so translating it by a power
//! of ten up to 1e6 (where f32 spacing is 1/16) leaves the geometry exact: what changes
//! is only the precision of the ray arithmetic, which is what is under test.

use glam::Vec3;

use super::reference::{Prim, RefScene};
use super::{Budget, Rendered, Row, render_ron, v3};
use glint::scene::Camera;

/// Where the unit scene is put: `world = scale * p + offset`.
#[derive(Clone, Copy, Debug)]
struct Place {
    scale: f32,
    offset: Vec3,
}

impl Place {
    fn p(&self, p: Vec3) -> Vec3 {
        self.scale * p + self.offset
    }
    fn v(&self, v: Vec3) -> Vec3 {
        self.scale * v
    }
    /// Distance below which the f32 render cannot place a shadow edge in the placed scene:
    /// eight f32 spacings at its largest coordinate (a hit point's rounding error is up to
    /// about three, and the offset off the surface about 3.5 more), plus 1e-4 of the
    /// scene's size.
    fn margin(&self) -> f64 {
        let extent = self.offset.abs().max_element() as f64 + 8.0 * self.scale as f64;
        1e-4 * self.scale as f64 + 8.0 * f32::EPSILON as f64 * extent
    }
}

const EYE: Vec3 = Vec3::new(0.0, 2.5, 6.0);
const TARGET: Vec3 = Vec3::new(0.0, 0.5, 0.0);
const FLOOR: Vec3 = Vec3::new(-4.0, 0.0, -4.0);
const BALL: Vec3 = Vec3::new(-1.25, 0.75, 0.5);
const BALL_R: f32 = 0.75;
const BOX: Vec3 = Vec3::new(1.25, 0.5, -0.5);
const LIGHT: Vec3 = Vec3::new(2.0, 5.0, 3.0);
/// Diffuse colour of everything; with shading off and a white light a lit pixel is this.
const KD: f32 = 0.5;

/// The scene as RON. `full`: phong, a reflective ball and an area light as well;
/// otherwise shading off and the point light alone (the acne/leak probe).
fn scene(place: Place, width: u32, height: u32, full: bool) -> String {
    let settings = if full {
        "(shading_model: phong, shadow_samples: 4)"
    } else {
        "(shading: false, reflections: false)"
    };
    let ks = if full { 0.25 } else { 0.0 };
    let area = if full {
        format!(
            "ParallelogramLight((v0: {}, edge01: {}, edge02: {}, color0: (0.5, 0.5, 0.5), color1: (0.5, 0.5, 0.5), color2: (0.5, 0.5, 0.5), color3: (0.5, 0.5, 0.5))),",
            v3(place.p(Vec3::new(-1.0, 4.0, -1.0))),
            v3(place.v(Vec3::X)),
            v3(place.v(Vec3::Z))
        )
    } else {
        String::new()
    };
    format!(
        r#"(
    camera: (position: {eye}, look_at: {target}, fov_y: 40.0, width: {width}, height: {height}),
    settings: {settings},
    materials: {{
        "floor": (kd: ({KD}, {KD}, {KD})),
        "ball": (kd: ({KD}, {KD}, {KD}), ks: ({ks}, {ks}, {ks}), shininess: 32.0),
        "box": (kd: ({KD}, {KD}, {KD})),
    }},
    entities: [
        Mesh((geometry: Parallelogram(origin: {floor}, edge_u: {eu}, edge_v: {ev}), material: Some("floor"))),
        Sphere((center: {ball}, radius: {r:?}, material: "ball")),
        Mesh((geometry: Cube, material: Some("box"), transform: (translate: {bx}, scale: {bs}))),
        PointLight((position: {light}, color: (1.0, 1.0, 1.0))),
        {area}
    ],
)"#,
        eye = v3(place.p(EYE)),
        target = v3(place.p(TARGET)),
        floor = v3(place.p(FLOOR)),
        eu = v3(place.v(Vec3::new(0.0, 0.0, 8.0))),
        ev = v3(place.v(Vec3::new(8.0, 0.0, 0.0))),
        ball = v3(place.p(BALL)),
        r = place.scale * BALL_R,
        bx = v3(place.p(BOX)),
        bs = v3(place.v(Vec3::ONE)),
        light = v3(place.p(LIGHT)),
    )
}

/// The probe scene in f64, placed the same way.
fn reference(place: Place) -> RefScene {
    let p = |v: Vec3| place.p(v).as_dvec3();
    let v = |v: Vec3| place.v(v).as_dvec3();
    RefScene {
        prims: vec![
            Prim::Rect {
                origin: p(FLOOR),
                u: v(Vec3::new(0.0, 0.0, 8.0)),
                v: v(Vec3::new(8.0, 0.0, 0.0)),
            },
            Prim::Sphere {
                center: p(BALL),
                radius: (place.scale * BALL_R) as f64,
            },
            Prim::Cuboid {
                min: p(BOX) - v(Vec3::splat(0.5)),
                max: p(BOX) + v(Vec3::splat(0.5)),
            },
        ],
        light: p(LIGHT),
        margin: place.margin(),
    }
}

fn camera(place: Place, b: &Budget) -> Camera {
    Camera {
        position: place.p(EYE),
        look_at: place.p(TARGET),
        up: Vec3::Y,
        fov_y_degrees: 40.0,
        width: b.width,
        height: b.height(),
    }
}

/// Renders the full scene and the probe, and measures them against `unit` (the full
/// render at unit scale, no offset) with `image_bound` on the mean difference.
fn measure(
    case: &str,
    place: Place,
    b: &Budget,
    unit: Option<&Rendered>,
    image_bound: f64,
) -> Vec<Row> {
    let mut rows = Vec::new();
    let full = match render_ron(&scene(place, b.width, b.height(), true)) {
        Ok(r) => r,
        Err(e) => return vec![Row::error(case, e)],
    };
    let probe = match render_ron(&scene(place, b.width, b.height(), false)) {
        Ok(r) => r,
        Err(e) => return vec![Row::error(case, e)],
    };
    rows.push(Row::finite(case, full.nonfinite() + probe.nonfinite()));
    if let Some(unit) = unit {
        rows.push(Row::at_most(
            case,
            "mean |image - reference image|",
            full.mean_diff(unit),
            image_bound,
        ));
    }
    let counts = reference(place).count(&camera(place, b), &probe, Vec3::splat(KD));
    let total = (probe.width * probe.height) as f64;
    rows.push(Row::at_most(
        case,
        "acne pixels (lit expected, dark rendered)",
        counts.acne as f64,
        0.0,
    ));
    rows.push(Row::at_most(
        case,
        "leak pixels (dark expected, lit rendered)",
        counts.leaks as f64,
        0.0,
    ));
    rows.push(Row::at_most(
        case,
        "hits where the reference misses",
        counts.wrong_miss as f64,
        0.0,
    ));
    // The check must look at much of the image, or it proves nothing. At 1e6 from the
    // origin f32 resolves 1/16 of a unit, so the band around each edge of this unit-sized
    // scene is wide.
    rows.push(Row::at_most(
        case,
        "pixels too near a boundary to judge (fraction)",
        counts.unknown as f64 / total,
        0.6,
    ));
    rows
}

/// Case 1: scale invariance and no acne from 1e-4 to 1e6.
pub fn scale(b: &Budget) -> Vec<Row> {
    let unit_place = Place {
        scale: 1.0,
        offset: Vec3::ZERO,
    };
    let unit = match render_ron(&scene(unit_place, b.width, b.height(), true)) {
        Ok(r) => r,
        Err(e) => return vec![Row::error("scale", e)],
    };
    let mut rows = Vec::new();
    for s in [1e-4f32, 1e-2, 1.0, 1e2, 1e4, 1e6] {
        let place = Place {
            scale: s,
            offset: Vec3::ZERO,
        };
        // Same relative precision at every scale: only silhouette pixels may flip.
        rows.extend(measure(
            &format!("scale {s:e}"),
            place,
            b,
            Some(&unit),
            2e-3,
        ));
    }
    rows
}

/// Case 2: the unit scene far from the origin.
pub fn far(b: &Budget) -> Vec<Row> {
    let unit_place = Place {
        scale: 1.0,
        offset: Vec3::ZERO,
    };
    let unit = match render_ron(&scene(unit_place, b.width, b.height(), true)) {
        Ok(r) => r,
        Err(e) => return vec![Row::error("far", e)],
    };
    let mut rows = Vec::new();
    for t in [1e3f32, 1e5, 1e6] {
        let place = Place {
            scale: 1.0,
            offset: Vec3::new(t, t, -t),
        };
        // Hit points carry an error of about one f32 spacing at t (1/16 at 1e6), which
        // moves shading normals and shadow edges by that much on a unit-sized scene.
        let spacing = t as f64 * f32::EPSILON as f64;
        rows.extend(measure(
            &format!("offset {t:e}"),
            place,
            b,
            Some(&unit),
            2e-3 + 0.5 * spacing,
        ));
    }
    rows
}
