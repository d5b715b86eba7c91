//! Generators shared by unit tests, system tests, the stress suite and the benchmarks:
//! a tiny deterministic random stream and closed test meshes. (Rendering never uses the
//! stream: its random numbers are counter-based, see `sampling`.)

use glam::{Vec3, vec3};

/// Pearson's chi-square statistic of `counts` against a uniform spread of their total
/// over the bins (degrees of freedom: bins - 1).
pub fn chi_square(counts: &[u32]) -> f64 {
    let total: f64 = counts.iter().map(|&c| f64::from(c)).sum();
    let expected = total / counts.len() as f64;
    counts
        .iter()
        .map(|&c| (f64::from(c) - expected).powi(2) / expected)
        .sum()
}

/// Small deterministic random stream (a 64-bit LCG), so tests need no extra crate.
pub struct Lcg(pub u64);

impl Lcg {
    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    /// Uniform in `0..n` (`n` at most 2^24).
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.next_f32() * n as f32) as u32).min(n - 1)
    }
    /// Uniform in the unit cube.
    pub fn vec(&mut self) -> Vec3 {
        vec3(self.next_f32(), self.next_f32(), self.next_f32())
    }
    /// Uniform unit direction.
    pub fn dir(&mut self) -> Vec3 {
        loop {
            let v = self.vec() * 2.0 - Vec3::ONE;
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

/// An indexed triangle mesh.
pub struct Mesh {
    /// Vertex positions.
    pub verts: Vec<Vec3>,
    /// Vertex index triples.
    pub tris: Vec<[u32; 3]>,
}

impl Mesh {
    /// The corners of triangle `i`.
    pub fn tri(&self, i: usize) -> (Vec3, Vec3, Vec3) {
        let [a, b, c] = self.tris[i];
        (
            self.verts[a as usize],
            self.verts[b as usize],
            self.verts[c as usize],
        )
    }
}

/// An axis-aligned box with awkward (non-dyadic) corners, two triangles per face.
pub fn cube(min: Vec3, max: Vec3) -> Mesh {
    let verts = (0..8)
        .map(|i| {
            vec3(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            )
        })
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut tris = Vec::new();
    for q in quads {
        tris.push([q[0], q[1], q[2]]);
        tris.push([q[0], q[2], q[3]]);
    }
    Mesh { verts, tris }
}

/// A unit icosphere with shared vertices, subdivided `levels` times (the scene's own shape).
pub fn icosphere(levels: u32) -> Mesh {
    let m = crate::scene::shapes::icosphere(levels);
    Mesh {
        verts: m.vertices.iter().map(|v| v.position).collect(),
        tris: m.triangles,
    }
}
