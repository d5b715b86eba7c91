//! What glint's benchmarks share: procedural meshes, the rays traced against
//! them (primary, incoherent, shadow), glint's queries on triangle soups, the
//! real models of `../shared/assets`, (in [`embree`]) Embree 4 loaded at run
//! time, and (in [`tinybvh`]) tinybvh's BVH8_CPU compiled by build.rs.

use std::path::{Path, PathBuf};

use glam::{Vec3, vec3};
use glint::accel::{
    Aabb, Bvh, Ray, RayShear, SplitMethod, TwoLevelBvh, WideBvh, intersect_triangle_sheared,
};
use glint::test_util::Lcg;

pub mod embree;
pub mod tinybvh;

/// A lat-long sphere of `n × n` quads, displaced by a few sines and a little
/// per-vertex noise, so that it has detail at several scales. Pole triangles
/// that would be degenerate are left out.
pub fn displaced_sphere(n: usize) -> Vec<[Vec3; 3]> {
    let mut rng = Lcg(12345);
    let cols = n;
    let rows = n;
    let mut verts = Vec::with_capacity((rows + 1) * cols);
    for i in 0..=rows {
        let theta = std::f32::consts::PI * i as f32 / rows as f32;
        for j in 0..cols {
            let phi = std::f32::consts::TAU * j as f32 / cols as f32;
            let r = 1.0
                + 0.08 * (9.0 * theta).sin() * (7.0 * phi).cos()
                + 0.03 * (31.0 * theta + 2.0).sin() * (29.0 * phi).sin()
                + 0.004 * (rng.next_f32() - 0.5);
            verts.push(
                r * vec3(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ),
            );
        }
    }
    let at = |i: usize, j: usize| verts[i * cols + j % cols];
    let mut tris = Vec::with_capacity(2 * rows * cols);
    for i in 0..rows {
        for j in 0..cols {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            if i != 0 {
                tris.push([a, b, c]);
            }
            if i != rows - 1 {
                tris.push([a, c, d]);
            }
        }
    }
    tris
}

/// Where the rays come from: a camera, a point light, and how far ray origins
/// leave the surface.
pub struct View {
    pub eye: Vec3,
    pub target: Vec3,
    pub fov_y_degrees: f32,
    pub light: Vec3,
    pub offset: f32,
    /// Orient normals away from this point (the mesh is star-shaped about it);
    /// `None` keeps the winding's normal (incoherent rays pick a side anyway)
    /// and offsets shadow-ray origins towards the light.
    pub star_centre: Option<Vec3>,
}

impl View {
    /// The procedural sphere: seen from +z, lit from above right.
    pub fn sphere() -> Self {
        Self {
            eye: vec3(0.3, 0.4, 3.0),
            target: Vec3::ZERO,
            fov_y_degrees: 40.0,
            light: vec3(2.0, 3.0, 2.5),
            offset: 1e-3,
            star_centre: Some(Vec3::ZERO),
        }
    }

    /// A model: glint's automatic camera framing the bounds, and glint's
    /// default point light (above and to the left of the eye).
    pub fn framing(tris: &[[Vec3; 3]]) -> Self {
        let (lo, hi) = tris
            .iter()
            .flatten()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let (centre, radius) = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
        let cam = glint::scene::model::framing_camera(centre, radius, 256, 256);
        let eye = cam.position - centre;
        let up_left = vec3(-0.5, 1.0, 0.0) * eye.length();
        Self {
            eye: cam.position,
            target: cam.look_at,
            fov_y_degrees: cam.fov_y_degrees,
            light: centre + (eye + up_left) * 1.2,
            offset: 1e-4 * radius,
            star_centre: None,
        }
    }
}

/// Pinhole camera grid looking from `view.eye` at `view.target`.
pub fn primary_rays(view: &View, w: usize, h: usize) -> Vec<Ray> {
    let eye = view.eye;
    let fwd = (view.target - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let tan = (view.fov_y_degrees.to_radians() * 0.5).tan();
    let mut rays = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let u = ((x as f32 + 0.5) / w as f32 * 2.0 - 1.0) * tan;
            let v = (1.0 - (y as f32 + 0.5) / h as f32 * 2.0) * tan;
            rays.push(Ray::new(eye, (fwd + u * right + v * up).normalize()));
        }
    }
    rays
}

/// Random surface points (with their geometric normals).
pub fn surface_points(
    tris: &[[Vec3; 3]],
    n: usize,
    star_centre: Option<Vec3>,
    rng: &mut Lcg,
) -> Vec<(Vec3, Vec3)> {
    (0..n)
        .map(|_| {
            let [a, b, c] =
                tris[((rng.next_f32() * tris.len() as f32) as usize).min(tris.len() - 1)];
            let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = a + u * (b - a) + v * (c - a);
            let nrm = (b - a).cross(c - a).normalize_or_zero();
            match star_centre {
                Some(c) if nrm.dot(p - c) < 0.0 => (p, -nrm),
                _ => (p, nrm),
            }
        })
        .collect()
}

/// Random origins just off the surface (either side), random directions.
pub fn incoherent_rays(tris: &[[Vec3; 3]], view: &View, n: usize) -> Vec<Ray> {
    let mut rng = Lcg(777);
    surface_points(tris, n, view.star_centre, &mut rng)
        .into_iter()
        .map(|(p, nrm)| {
            let side = if rng.next_f32() < 0.5 { 1.0 } else { -1.0 };
            Ray::new(p + side * view.offset * nrm, rng.dir())
        })
        .collect()
}

/// Shadow rays from points just off the surface (outside a star-shaped mesh,
/// else on the light's side) to the point light; t in (0, 1).
pub fn shadow_rays(tris: &[[Vec3; 3]], view: &View, n: usize) -> Vec<Ray> {
    let light = view.light;
    let mut rng = Lcg(999);
    surface_points(tris, n, view.star_centre, &mut rng)
        .into_iter()
        .map(|(p, nrm)| {
            let nrm = match view.star_centre {
                None if nrm.dot(light - p) < 0.0 => -nrm,
                _ => nrm,
            };
            let o = p + view.offset * nrm;
            Ray::new(o, light - o)
        })
        .collect()
}

/// glint's closest hit (triangle index, t) through its BVH and watertight test.
pub fn glint_closest(bvh: &Bvh, tris: &[[Vec3; 3]], ray: &Ray) -> Option<(u32, f32)> {
    let s = RayShear::new(ray);
    bvh.closest_hit(ray, f32::INFINITY, &mut (), |p, t_max| {
        let [a, b, c] = tris[p as usize];
        intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max).map(|h| h.t)
    })
}

/// glint's any-hit query for t in (0, 1).
pub fn glint_occluded(bvh: &Bvh, tris: &[[Vec3; 3]], ray: &Ray) -> bool {
    let s = RayShear::new(ray);
    bvh.any_hit(ray, 1.0, &mut (), |p| {
        let [a, b, c] = tris[p as usize];
        intersect_triangle_sheared(&s, ray.origin, a, b, c, 1.0).is_some()
    })
}

/// glint's binary BVH over `tris`, built as a render builds it (binned SAH, spatial splits).
pub fn glint_binary(tris: &[[Vec3; 3]]) -> Bvh {
    Bvh::build_triangles(tris, SplitMethod::SahBinned)
}

/// glint's 8-wide BVH over `tris`, built as a render builds it ([`glint_binary`], collapsed).
pub fn glint_wide(tris: &[[Vec3; 3]]) -> WideBvh {
    WideBvh::collapse(&glint_binary(tris), tris)
}

/// The boxes of `tris`, one a triangle.
pub fn triangle_boxes(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
    tris.iter().map(|t| Aabb::from_points(t)).collect()
}

/// glint's 8-wide BVH over `tris` without spatial splits: the binned SAH build over the
/// triangles' boxes, collapsed (the like of Embree's medium build).
pub fn glint_wide_objects(tris: &[[Vec3; 3]]) -> WideBvh {
    WideBvh::collapse(
        &Bvh::build(&triangle_boxes(tris), SplitMethod::SahBinned),
        tris,
    )
}

/// Traces `rays` one at a time through `wide` as the anchors time glint: any hit in
/// (0, 1) for shadow rays, else the closest hit; returns how many rays hit.
pub fn glint_wide_hits(wide: &WideBvh, rays: &[Ray], shadow: bool) -> u32 {
    rays.iter()
        .map(|r| {
            if shadow {
                wide.any_hit(r, 1.0, |_, _| true)
            } else {
                wide.closest_hit(r, f32::INFINITY).is_some()
            }
        })
        .map(u32::from)
        .sum()
}

/// The first file in `dir` whose name ends with `.{ext}` (in name order).
pub fn find_file(dir: &Path, ext: &str) -> Result<PathBuf, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)))
        .collect();
    files.sort();
    files
        .into_iter()
        .next()
        .ok_or_else(|| format!("no .{ext} file in {}", dir.display()))
}

/// World-space triangles exactly as glint renders them: the model imported
/// by glint's own importer, prepared by its Prepare schedule, every instance of
/// a shared mesh flattened into its own copy.
pub fn load_model(path: &Path) -> Result<Vec<[Vec3; 3]>, String> {
    load_instanced(path).map(|(tris, ..)| tris)
}

/// [`load_model`]'s triangles, of which the render keeps the first `.1` (the meshes
/// drawn once) flattened, and the two-level BVH it keeps the rest in (the meshes drawn
/// more than once; empty when there is none), from one import.
pub fn load_instanced(path: &Path) -> Result<(Vec<[Vec3; 3]>, usize, TwoLevelBvh), String> {
    let renderer = glint::Renderer::from_file(path, &Default::default())
        .and_then(|mut r| r.prepare().map(|()| r))
        .map_err(|e| e.to_string())?;
    let geometry = renderer
        .world
        .resource::<glint::trace::geometry::SceneGeometry>();
    let mut tris = geometry.all_positions();
    let flattened = tris.len();
    let two = geometry.instanced.clone();
    for instance in &two.instances {
        let mesh = &two.meshes[instance.mesh as usize];
        let m = &instance.world_from_object;
        tris.extend(
            mesh.positions()
                .into_iter()
                .map(|t| t.map(|v| m.transform_point3(v))),
        );
    }
    Ok((tris, flattened, two))
}

/// `println!` for the examples through [`glint::terminal::print_stdout`]: a reader that
/// has gone away (`| head -1`) ends the process quietly instead of the panic `println!`
/// raises on a closed pipe.
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::print_line(&format!($($arg)*))
    };
}

/// Writes `text` and a newline to standard output (see [`outln!`]).
pub fn print_line(text: &str) {
    glint::terminal::print_stdout(&format!("{text}\n"));
}

/// `../shared/assets` next to the checkout, if present.
pub fn assets_dir() -> Option<PathBuf> {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/assets"));
    dir.is_dir().then(|| dir.to_path_buf())
}

/// A torus (major radius 1, minor 0.35) of `2 n × n` quads (`4 n²` triangles) lying in the xz
/// plane, displaced along its normals by a few sines and per-vertex noise, on
/// a ground plane of two triangles just below it.
pub fn displaced_torus(n: usize) -> Vec<[Vec3; 3]> {
    let mut rng = Lcg(4242);
    let (cols, rows) = (2 * n, n);
    let mut verts = Vec::with_capacity(rows * cols);
    for i in 0..rows {
        let theta = std::f32::consts::TAU * i as f32 / rows as f32;
        for j in 0..cols {
            let phi = std::f32::consts::TAU * j as f32 / cols as f32;
            let r = 0.35
                + 0.04 * (7.0 * theta).sin() * (11.0 * phi).cos()
                + 0.015 * (23.0 * theta + 1.0).sin() * (37.0 * phi).sin()
                + 0.003 * (rng.next_f32() - 0.5);
            let ring = 1.0 + r * theta.cos();
            verts.push(vec3(ring * phi.cos(), r * theta.sin(), ring * phi.sin()));
        }
    }
    let at = |i: usize, j: usize| verts[(i % rows) * cols + j % cols];
    let mut tris = Vec::with_capacity(2 * rows * cols + 2);
    for i in 0..rows {
        for j in 0..cols {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    let (g, y) = (3.0, -0.42);
    let ground = [
        vec3(-g, y, -g),
        vec3(g, y, -g),
        vec3(g, y, g),
        vec3(-g, y, g),
    ];
    tris.push([ground[0], ground[2], ground[1]]);
    tris.push([ground[0], ground[3], ground[2]]);
    tris
}

impl View {
    /// The procedural torus: seen from above the front, lit from above right.
    /// Normals keep their winding (the torus is not star-shaped).
    pub fn torus() -> Self {
        Self {
            eye: vec3(0.4, 1.6, 2.6),
            target: vec3(0.0, -0.1, 0.0),
            fov_y_degrees: 45.0,
            light: vec3(2.0, 3.0, 1.5),
            offset: 1e-3,
            star_centre: None,
        }
    }

    /// `scenes/cornell_box_parallelogram_light.ron` (the whole-render benchmark's
    /// scene): its camera, and its light's centre as the point light.
    pub fn cornell() -> Self {
        Self {
            eye: vec3(0.0, 1.0, 3.9),
            target: vec3(0.0, 1.0, 0.0),
            fov_y_degrees: 40.0,
            light: vec3(0.0, 1.99, 0.0),
            offset: 1e-4,
            star_centre: None,
        }
    }
}

/// The whole-render benchmark's scene file, in the repository.
pub fn cornell_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell_box_parallelogram_light.ron")
}

/// Nanoseconds the calling thread has run on a CPU (Linux: its CPU-time clock, read to
/// the nanosecond, where `/proc/thread-self/schedstat` moves only at scheduler ticks of
/// ~4 ms; 0 elsewhere).
pub fn thread_cpu_ns() -> u64 {
    #[cfg(target_os = "linux")]
    return clock_ns(rustix::time::ClockId::ThreadCPUTime);
    #[cfg(not(target_os = "linux"))]
    0
}

/// Nanoseconds all the process's threads have run on a CPU (as [`thread_cpu_ns`]).
pub fn process_cpu_ns() -> u64 {
    #[cfg(target_os = "linux")]
    return clock_ns(rustix::time::ClockId::ProcessCPUTime);
    #[cfg(not(target_os = "linux"))]
    0
}

#[cfg(target_os = "linux")]
fn clock_ns(id: rustix::time::ClockId) -> u64 {
    let t = rustix::time::clock_gettime(id);
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}
