//! The transparent surfaces one shadow ray crosses, for `SceneGeometry::transmittance`.

use glam::Vec2;

/// A transparent surface a shadow ray crosses: (t, material, texture coordinate).
pub(super) type Crossing = (f32, u32, Vec2);

/// Crossings of one shadow ray: the first few inline, so that the common case (a handful
/// of glass surfaces) costs no allocation per ray; more spill to the heap.
#[derive(Default)]
pub(super) struct Crossings {
    inline: [Crossing; 8],
    len: usize,
    spill: Vec<Crossing>,
}

impl Crossings {
    pub(super) fn push(&mut self, c: Crossing) {
        if self.len < self.inline.len() {
            self.inline[self.len] = c;
            self.len += 1;
        } else {
            self.spill.push(c);
        }
    }

    /// All crossings in order of t, then material and texture coordinate: equal
    /// crossings (one triangle met in two leaves, which a spatial split leaves it in)
    /// lie side by side, and which of a shared edge's twins comes first does not depend
    /// on the order the BVH met them.
    pub(super) fn sorted(&mut self) -> &[Crossing] {
        let all = if self.spill.is_empty() {
            &mut self.inline[..self.len]
        } else {
            self.spill.extend_from_slice(&self.inline[..self.len]);
            &mut self.spill[..]
        };
        all.sort_unstable_by(|a, b| {
            let key = |c: &Crossing| (c.1, c.2.x.to_bits(), c.2.y.to_bits());
            a.0.total_cmp(&b.0).then_with(|| key(a).cmp(&key(b)))
        });
        all
    }
}
