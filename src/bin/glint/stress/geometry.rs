//! Cases 3 to 5, traced on the scene geometry directly: watertightness of closed meshes,
//! axis-aligned and grazing rays (BVH against brute force), degenerate triangles.

use glam::{Affine3A, DVec3, Quat, Vec2, Vec3};
use rayon::prelude::*;

use super::{Budget, Row, render, v3};
use glint::accel::{Aabb, Bvh, Ray, SplitMethod};
use glint::render::Renderer;
use glint::scene::components::MeshData;
use glint::scene::{Sphere, parse_scene, shapes};
pub use glint::test_util::Lcg;
use glint::trace::geometry::{Hit, SceneGeometry};
use glint::trace::surface::surface_at;

/// World-space triangles of `mesh` under `m`.
fn place(mesh: &MeshData, m: Affine3A) -> Vec<[Vec3; 3]> {
    mesh.triangles
        .iter()
        .map(|t| t.map(|i| m.transform_point3(mesh.vertices[i as usize].position)))
        .collect()
}

/// Scene geometry over `tris` and `spheres`, with a BVH (`bvh`) or one leaf (brute force).
pub fn geometry_of(
    tris: &[[Vec3; 3]],
    spheres: &[Sphere],
    bvh: Option<SplitMethod>,
) -> SceneGeometry {
    let build = |bounds: &[Aabb]| match bvh {
        Some(split) => Bvh::build(bounds, split),
        None => Bvh::single_leaf(bounds),
    };
    let tri_bounds: Vec<Aabb> = tris.iter().map(|p| Aabb::from_points(p)).collect();
    let sphere_bounds: Vec<Aabb> = spheres
        .iter()
        .map(|s| {
            Aabb::new(
                s.center - Vec3::splat(s.radius),
                s.center + Vec3::splat(s.radius),
            )
        })
        .collect();
    let mut g = SceneGeometry {
        tri_normals: tris.iter().map(|_| [Vec3::Z; 3]).collect(),
        tri_texcoords: tris.iter().map(|_| [Vec2::ZERO; 3]).collect(),
        tri_material: vec![0; tris.len()],
        tri_bvh: match bvh {
            Some(split) => Bvh::build_triangles(tris, split),
            None => Bvh::single_leaf(&tri_bounds),
        },
        spheres: spheres.to_vec(),
        sphere_material: vec![0; spheres.len()],
        sphere_bvh: build(&sphere_bounds),
        ..Default::default()
    };
    // The render's queries traverse the wide BVH: stress it too.
    g.collapse_triangle_bvh(tris);
    g
}

/// A closed cone whose side and base are fans of `n` thin triangles around one vertex.
fn cone(n: u32) -> MeshData {
    use glint::scene::components::Vertex;
    let vertex = |p: Vec3| Vertex {
        position: p,
        normal: Vec3::Y,
        texcoord: Vec2::ZERO,
    };
    let mut vertices = vec![vertex(Vec3::new(0.0, 1.0, 0.0)), vertex(Vec3::ZERO)];
    for i in 0..n {
        let a = std::f32::consts::TAU * i as f32 / n as f32;
        vertices.push(vertex(Vec3::new(a.cos(), 0.0, a.sin())));
    }
    let mut triangles = Vec::new();
    for i in 0..n {
        let (a, b) = (2 + i, 2 + (i + 1) % n);
        triangles.push([0, b, a]);
        triangles.push([1, a, b]);
    }
    MeshData {
        vertices,
        triangles,
    }
}

/// Points exactly on the vertices and shared edges of `tris` (several fractions per edge),
/// skipping edges whose both ends satisfy `skip`.
fn edge_points(tris: &[[Vec3; 3]], rng: &mut Lcg, count: usize) -> Vec<Vec3> {
    let mut pts = Vec::with_capacity(count);
    while pts.len() < count {
        for t in tris {
            for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                pts.push(p);
                for f in [0.5, 0.25, rng.next_f32(), rng.next_f32()] {
                    pts.push(p.lerp(q, f));
                }
            }
            if pts.len() >= count {
                break;
            }
        }
    }
    pts
}

/// Rays from outside and inside through edge and vertex points, and random rays from
/// inside; returns (rays, misses).
fn closed_mesh_misses(
    g: &SceneGeometry,
    tris: &[[Vec3; 3]],
    centre: Vec3,
    size: f32,
    count: usize,
    seed: u64,
) -> (usize, usize) {
    let mut rng = Lcg(seed);
    let pts = edge_points(tris, &mut rng, count / 3);
    let mut rays = Vec::with_capacity(pts.len() * 3);
    for &p in &pts {
        // From outside along a line through the centre (the mesh is convex): it crosses
        // the surface at p, so it must hit.
        let o = centre + (p - centre) * (2.0 + rng.next_f32());
        rays.push(Ray::new(o, p - o));
        // From a random inside point through p.
        let o = centre + (rng.vec() - Vec3::splat(0.5)) * (0.1 * size);
        rays.push(Ray::new(o, p - o));
        rays.push(Ray::new(
            centre + (rng.vec() - Vec3::splat(0.5)) * (0.1 * size),
            rng.dir(),
        ));
    }
    let misses = rays
        .par_iter()
        .filter(|r| g.intersect(r, f32::INFINITY, &mut ()).is_none())
        .count();
    (rays.len(), misses)
}

/// Case 3: no ray slips through a shared edge or vertex.
pub fn watertight(b: &Budget) -> Vec<Row> {
    let mut rows = Vec::new();
    let awkward = |scale: Vec3, off: Vec3| {
        Affine3A::from_scale_rotation_translation(
            scale,
            Quat::from_euler(glam::EulerRot::XYZ, 0.3137, -0.771, 0.0913),
            off,
        )
    };
    let off = Vec3::new(0.3137, -1.771, 2.0913);
    let meshes: [(&str, MeshData, Affine3A, Vec3, f32); 3] = [
        (
            "icosphere",
            shapes::icosphere(4),
            awkward(Vec3::splat(1.37), off),
            off,
            1.37,
        ),
        (
            "cube (2 triangles per face)",
            shapes::cube(),
            awkward(Vec3::new(1.832, 2.1447, 0.8441), off),
            off,
            0.8,
        ),
        // The centroid of the cone (height 1, radius 1) is at y = 1/4.
        (
            "cone of thin fans",
            cone(if b.full { 5000 } else { 1000 }),
            awkward(Vec3::new(0.9173, 1.3, 0.9173), off),
            off,
            0.5,
        ),
    ];
    for (name, mesh, m, _, size) in meshes {
        let tris = place(&mesh, m);
        let centre = if name.starts_with("cone") {
            m.transform_point3(Vec3::new(0.0, 0.25, 0.0))
        } else {
            m.transform_point3(Vec3::ZERO)
        };
        let g = geometry_of(&tris, &[], Some(SplitMethod::SahBinned));
        let (n, misses) = closed_mesh_misses(&g, &tris, centre, size, b.rays, 7);
        let case = format!("watertight {name}");
        rows.push(Row::at_most(
            &case,
            format!("rays through edges/vertices missing (of {n})"),
            misses as f64,
            0.0,
        ));
    }
    rows
}

/// The closest hit by both traversals; counts disagreements and non-finite results.
fn compare(bvh: &SceneGeometry, brute: &SceneGeometry, rays: &[Ray]) -> (usize, usize) {
    let finite = |h: &Option<Hit>| h.is_none_or(|h| h.t.is_finite() && h.bary.is_finite());
    rays.par_iter()
        .map(|r| {
            let a = bvh.intersect(r, f32::INFINITY, &mut ());
            let c = brute.intersect(r, f32::INFINITY, &mut ());
            let differ = match (a, c) {
                (None, None) => false,
                // On a shared edge, or where coplanar triangles overlap (the boxes' faces
                // touch), the candidates' t differ by rounding and which one wins depends on
                // the visiting order: equal within rounding of the hit point's coordinates.
                (Some(a), Some(c)) => {
                    let len = r.dir.length();
                    let scale = r.origin.abs().max_element() + a.t.max(c.t) * len;
                    (a.t - c.t).abs() * len > 16.0 * f32::EPSILON * scale || a.kind != c.kind
                }
                _ => true,
            };
            (differ as usize, (!finite(&a) || !finite(&c)) as usize)
        })
        .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1))
}

/// Case 4: axis-aligned rays (infinite inverse direction), rays in box-face planes and
/// grazing rays: BVH and brute force agree exactly, nothing is NaN, nothing is missed.
pub fn axis_grazing(b: &Budget) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut tris = Vec::new();
    // A floor of 32x32 cells at y = 0 (8 units wide) and a staircase of boxes whose faces
    // share planes, so many BVH boxes are flat or touch the rays' planes exactly.
    tris.extend(place(
        &shapes::plane(32),
        Affine3A::from_scale(Vec3::new(8.0, 1.0, 8.0)),
    ));
    for i in 0..6 {
        let fi = i as f32;
        let m = Affine3A::from_scale_rotation_translation(
            Vec3::new(0.5, 0.25 * (fi + 1.0), 0.5),
            Quat::IDENTITY,
            Vec3::new(-1.5 + 0.5 * fi, 0.125 * (fi + 1.0), 0.25),
        );
        tris.extend(place(&shapes::cube(), m));
    }
    tris.extend(place(
        &shapes::icosphere(2),
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.6),
            Quat::IDENTITY,
            Vec3::new(2.0, 0.6, -1.0),
        ),
    ));
    let spheres = [
        Sphere {
            center: Vec3::new(-2.0, 0.5, -1.5),
            radius: 0.5,
        },
        Sphere {
            center: Vec3::new(0.0, 1.5, -2.0),
            radius: 0.25,
        },
    ];
    let planes: Vec<f32> = tris.iter().flatten().flat_map(|p| p.to_array()).collect();
    let mut rng = Lcg(99);
    let pick =
        |rng: &mut Lcg| planes[(rng.next_f32() * planes.len() as f32) as usize % planes.len()];
    // Brute force is O(triangles) per ray: a tenth of the budget per kind of ray.
    let n = b.rays / 10;
    let mut axis = Vec::with_capacity(n);
    let mut one_zero = Vec::with_capacity(n);
    let mut in_plane = Vec::with_capacity(n);
    for _ in 0..n {
        // Origins with coordinates snapped onto vertex (hence slab) planes.
        let mut o = rng.vec() * Vec3::new(8.0, 3.0, 8.0) - Vec3::new(4.0, 0.5, 4.0);
        for k in 0..3 {
            if rng.next_f32() < 0.5 {
                o[k] = pick(&mut rng);
            }
        }
        let k = (rng.next_f32() * 3.0) as usize % 3;
        let mut d = Vec3::ZERO;
        d[k] = if rng.next_f32() < 0.5 { 1.0 } else { -1.0 };
        axis.push(Ray::new(o, d));
        let mut d = rng.dir();
        d[k] = 0.0;
        one_zero.push(Ray::new(o, d));
        // In the plane of a box face through o: the component along that face's normal is 0.
        let mut d = rng.dir();
        d[k] = 0.0;
        let mut o2 = o;
        o2[k] = pick(&mut rng);
        in_plane.push(Ray::new(o2, d));
    }
    // Grazing the floor: from height h, sloping down by h / 4 per unit, so the floor hit
    // is 4 units away (inside the floor, which spans 8 units), from 1e-2 down to 1e-6.
    let mut grazing = Vec::with_capacity(n);
    for i in 0..n {
        let h = 10f32.powf(-2.0 - 4.0 * (i as f32 / n as f32));
        let a = rng.next_f32() * std::f32::consts::TAU;
        let horizontal = Vec3::new(a.cos(), 0.0, a.sin());
        let target = Vec3::new(rng.next_f32() - 0.5, 0.0, rng.next_f32() - 0.5) * 2.0;
        let o = target - 4.0 * horizontal + Vec3::new(0.0, h, 0.0);
        grazing.push(Ray::new(o, target - o));
    }
    for (split, name) in [
        (SplitMethod::SahBinned, "sah"),
        (SplitMethod::Median, "median"),
    ] {
        let bvh = geometry_of(&tris, &spheres, Some(split));
        let brute = geometry_of(&tris, &spheres, None);
        for (kind, rays) in [
            ("axis-aligned rays", &axis),
            ("rays with one zero component", &one_zero),
            ("rays in box-face planes", &in_plane),
            ("grazing rays", &grazing),
        ] {
            let (differ, nonfinite) = compare(&bvh, &brute, rays);
            let case = format!("axis/grazing {name}");
            rows.push(Row::at_most(
                &case,
                format!(
                    "{kind}: BVH and brute force disagree (hit/miss, or t beyond rounding) (of {})",
                    rays.len()
                ),
                differ as f64,
                0.0,
            ));
            rows.push(Row::at_most(
                &case,
                format!("{kind}: non-finite hits"),
                nonfinite as f64,
                0.0,
            ));
        }
        // Every grazing ray reaches the floor (or something above it) before t = 1.
        let missed = grazing
            .par_iter()
            .filter(|r| {
                !bvh.intersect(r, f32::INFINITY, &mut ())
                    .is_some_and(|h| h.t <= 1.0 + 1e-5)
            })
            .count();
        rows.push(Row::at_most(
            format!("axis/grazing {name}"),
            "grazing rays missing the floor",
            missed as f64,
            0.0,
        ));
    }
    rows
}

/// True when the triangle's vertices are exactly collinear or coincide (exact in f64).
fn degenerate_tri(t: &[Vec3; 3]) -> bool {
    let (a, b, c) = (t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3());
    (b - a).cross(c - a) == DVec3::ZERO
}

/// Case 5: degenerate triangles load and render without NaN or panic and are never hit.
pub fn degenerate(b: &Budget) -> Vec<Row> {
    let case = "degenerate";
    let mut rows = Vec::new();
    let vert = |p: Vec3| format!("(position: {})", v3(p));
    let mut verts = Vec::new();
    let mut tris = Vec::new();
    let mut add = |ps: [Vec3; 3]| {
        let base = verts.len() as u32;
        verts.extend(ps.map(vert));
        tris.push(format!("({}, {}, {})", base, base + 1, base + 2));
    };
    // Zero-area: collinear, duplicate vertex, all three equal; on and off the axes.
    add([
        Vec3::new(-1.0, 0.5, 0.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::new(1.0, 0.5, 0.0),
    ]);
    add([
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(0.2, 0.4, 0.6),
        Vec3::new(0.4, 0.8, 1.2),
    ]);
    add([
        Vec3::new(0.3, 0.3, 0.0),
        Vec3::new(0.3, 0.3, 0.0),
        Vec3::new(-0.7, 0.9, 0.1),
    ]);
    add([Vec3::splat(0.25); 3]);
    // Needles: long and 1e-7 .. 1e-30 wide.
    add([
        Vec3::new(-1.0, -0.5, 0.0),
        Vec3::new(1.0, -0.5, 0.0),
        Vec3::new(0.0, -0.5 + 1e-7, 0.0),
    ]);
    add([
        Vec3::new(-1.0, -0.3, 0.2),
        Vec3::new(1.0, -0.3, 0.2),
        Vec3::new(0.3, -0.3, 0.2 + 1e-30),
    ]);
    let inline = format!(
        "Inline(vertices: [{}], triangles: [{}])",
        verts.join(", "),
        tris.join(", ")
    );
    // A mesh whose every vertex coincides, with explicit zero-length normals (repaired).
    let collapsed = "Inline(vertices: [(position: (0.5, 0.5, 0.5), normal: Some((0.0, 0.0, 0.0))), (position: (0.5, 0.5, 0.5)), (position: (0.5, 0.5, 0.5))], triangles: [(0, 1, 2), (2, 1, 0), (0, 0, 0)])";
    let text = format!(
        r#"(
    camera: (position: (0.0, 0.0, 3.0), look_at: (0.0, 0.0, 0.0), width: {w}, height: {h}),
    settings: (shading_model: phong),
    materials: {{ "m": (kd: (0.5, 0.5, 0.5), ks: (0.5, 0.5, 0.5), transparency: 0.5), "floor": (kd: (0.5, 0.5, 0.5)) }},
    entities: [
        Mesh((geometry: {inline}, material: Some("m"))),
        Mesh((geometry: {collapsed}, material: Some("m"))),
        Mesh((geometry: Parallelogram(origin: (-2.0, -2.0, -1.0), edge_u: (4.0, 0.0, 0.0), edge_v: (0.0, 4.0, 0.0)), material: Some("floor"))),
        PointLight((position: (0.0, 0.5, 2.0))),
        SegmentLight((endpoint0: (-1.0, 1.0, 1.0), endpoint1: (1.0, 1.0, 1.0))),
    ],
)"#,
        w = b.width,
        h = b.height()
    );
    let path = std::path::Path::new("<stress degenerate>.ron");
    let renderer = match parse_scene(&text, path).and_then(|f| Renderer::from_scene(&f, path)) {
        Ok(r) => r,
        Err(e) => return vec![Row::error(case, e)],
    };
    rows.push(Row::exactly(
        case,
        "load warnings (zero-length normal re-derived)",
        renderer.warnings().len() as f64,
        1.0,
    ));
    let rendered = match render(renderer) {
        Ok(r) => r,
        Err(e) => return vec![Row::error(case, e)],
    };
    rows.push(Row::finite(case, rendered.nonfinite()));

    // Trace straight at the degenerate triangles: the loaded, world-space geometry.
    let mut renderer = Renderer::from_scene(&parse_scene(&text, path).expect("parsed above"), path)
        .expect("loaded above");
    if let Err(e) = renderer.prepare() {
        return vec![Row::error(case, e)];
    }
    let g = renderer.world.resource::<SceneGeometry>();
    let positions = g.all_positions();
    let degenerate: Vec<bool> = positions.iter().map(degenerate_tri).collect();
    let mut rng = Lcg(5);
    let mut rays = Vec::new();
    for (i, t) in positions.iter().enumerate() {
        for k in 0..b.rays / 64 {
            let target = match k % 4 {
                0 => t[k % 3],
                1 => t[0].lerp(t[1], rng.next_f32()),
                2 => t[1].lerp(t[2], rng.next_f32()),
                _ => t[0].lerp(t[2], 0.5),
            };
            let o = target + rng.dir() * 3.0;
            rays.push((i, Ray::new(o, target - o)));
        }
    }
    let (hits_on_degenerate, nonfinite) = rays
        .par_iter()
        .map(|(_, r)| match g.intersect(r, f32::INFINITY, &mut ()) {
            Some(h) => {
                let s = surface_at(g, r, &h, true);
                let bad = !(h.t.is_finite()
                    && h.bary.is_finite()
                    && s.p.is_finite()
                    && s.n.is_finite()
                    && s.ng.is_finite()
                    && s.uv.is_finite()
                    && s.p_error.is_finite());
                (degenerate[h.prim as usize] as usize, bad as usize)
            }
            None => (0, 0),
        })
        .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1));
    let n_degenerate = degenerate.iter().filter(|&&d| d).count();
    rows.push(Row::exactly(
        case,
        "zero-area triangles in the loaded scene",
        n_degenerate as f64,
        8.0,
    ));
    rows.push(Row::at_most(
        case,
        format!(
            "hits reported on zero-area triangles (of {} rays)",
            rays.len()
        ),
        hits_on_degenerate as f64,
        0.0,
    ));
    rows.push(Row::at_most(
        case,
        "hits with a non-finite point, normal or uv",
        nonfinite as f64,
        0.0,
    ));
    rows
}
