//! Procedural meshes: the shapes a scene file can name, also used by tests,
//! the stress suite and the benchmarks.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use super::components::{MeshData, Vertex};

/// A parallelogram `origin + s*edge_u + t*edge_v` (s, t in \[0, 1\]) facing `edge_u x edge_v`.
pub fn parallelogram(origin: Vec3, edge_u: Vec3, edge_v: Vec3) -> MeshData {
    let normal = edge_u.cross(edge_v).normalize_or_zero();
    let corner = |s: f32, t: f32| Vertex {
        position: origin + s * edge_u + t * edge_v,
        normal,
        texcoord: Vec2::new(s, t),
    };
    MeshData {
        vertices: vec![
            corner(0.0, 0.0),
            corner(1.0, 0.0),
            corner(1.0, 1.0),
            corner(0.0, 1.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// The unit square [-0.5, 0.5]^2 in the xy plane, facing +z.
pub fn quad() -> MeshData {
    parallelogram(Vec3::new(-0.5, -0.5, 0.0), Vec3::X, Vec3::Y)
}

/// The unit square in the xz plane facing +y, split into `n x n` cells sharing vertices.
pub fn plane(n: u32) -> MeshData {
    let n = n.max(1);
    let mut vertices = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (s, t) = (i as f32 / n as f32, j as f32 / n as f32);
            vertices.push(Vertex {
                position: Vec3::new(s - 0.5, 0.0, 0.5 - t),
                normal: Vec3::Y,
                texcoord: Vec2::new(s, t),
            });
        }
    }
    let mut triangles = Vec::new();
    let row = n + 1;
    for j in 0..n {
        for i in 0..n {
            let a = j * row + i;
            triangles.push([a, a + 1, a + row + 1]);
            triangles.push([a, a + row + 1, a + row]);
        }
    }
    MeshData {
        vertices,
        triangles,
    }
}

/// The unit cube [-0.5, 0.5]^3: two triangles per face, flat outward normals.
pub fn cube() -> MeshData {
    let mut mesh = MeshData::default();
    let faces = [
        (Vec3::X, Vec3::NEG_Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
    ];
    for (n, u, v) in faces {
        let face = parallelogram(0.5 * (n - u - v), u, v);
        append(&mut mesh, &face);
    }
    mesh
}

/// A unit-radius UV sphere with smooth normals.
pub fn uv_sphere(segments: u32, rings: u32) -> MeshData {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut vertices = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            let p = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            vertices.push(Vertex {
                position: p,
                normal: p,
                texcoord: Vec2::new(s as f32 / segments as f32, 1.0 - r as f32 / rings as f32),
            });
        }
    }
    let row = segments + 1;
    let mut triangles = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            if r != 0 {
                triangles.push([a, c, b]);
            }
            if r != rings - 1 {
                triangles.push([b, c, d]);
            }
        }
    }
    MeshData {
        vertices,
        triangles,
    }
}

/// A unit-radius icosphere: an icosahedron with each face split in four `subdivisions` times.
/// Vertices are shared between faces, so the mesh is closed and watertight.
pub fn icosphere(subdivisions: u32) -> MeshData {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut points: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions.min(10) {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, points: &mut Vec<Vec3>| {
            let key = (a.min(b), a.max(b));
            *midpoints.entry(key).or_insert_with(|| {
                points.push((points[a as usize] + points[b as usize]).normalize());
                points.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut points);
            let bc = midpoint(b, c, &mut points);
            let ca = midpoint(c, a, &mut points);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    let vertices = points
        .iter()
        .map(|&p| Vertex {
            position: p,
            normal: p,
            texcoord: Vec2::new(
                0.5 + p.z.atan2(p.x) / std::f32::consts::TAU,
                0.5 + p.y.asin() / std::f32::consts::PI,
            ),
        })
        .collect();
    MeshData {
        vertices,
        triangles: faces,
    }
}

/// Appends `other`'s vertices and triangles to `mesh`.
pub fn append(mesh: &mut MeshData, other: &MeshData) {
    let base = mesh.vertices.len() as u32;
    mesh.vertices.extend_from_slice(&other.vertices);
    mesh.triangles
        .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
}

/// Area-weighted smooth vertex normals from the triangles (for files without normals).
/// A vertex touched only by degenerate triangles gets +z rather than NaN.
pub fn smooth_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    normals
        .into_iter()
        .map(|n| n.try_normalize().unwrap_or(Vec3::Z))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_outward(mesh: &MeshData) {
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize].position);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "triangle {t:?} faces inward");
        }
    }

    #[test]
    fn closed_shapes_face_outward() {
        assert_outward(&cube());
        assert_outward(&icosphere(2));
        assert_outward(&uv_sphere(12, 8));
    }

    #[test]
    fn icosphere_is_closed_and_shares_vertices() {
        let m = icosphere(2);
        assert_eq!(m.triangles.len(), 20 * 16);
        // Euler: V - E + F = 2 with E = 3F/2.
        assert_eq!(m.vertices.len() as i64 - 3 * 320 / 2 + 320, 2);
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(edges.values().all(|&n| n == 2));
    }

    #[test]
    fn plane_counts_and_normals() {
        let m = plane(4);
        assert_eq!(m.triangles.len(), 32);
        assert_eq!(m.vertices.len(), 25);
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.vertices[i as usize].position);
            assert!((b - a).cross(c - a).normalize().abs_diff_eq(Vec3::Y, 1e-6));
        }
    }

    #[test]
    fn smooth_normals_of_degenerate_triangles_are_finite() {
        let p = [Vec3::ZERO; 3];
        let n = smooth_normals(&p, &[[0, 1, 2]]);
        assert!(
            n.iter()
                .all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-6)
        );
    }
}
