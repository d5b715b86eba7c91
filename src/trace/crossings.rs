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

#[cfg(test)]
mod tests {
    use super::*;

    /// One triangle met in two leaves and another surface at the same t, in the order a
    /// traversal may meet them (A, B, A): sorted, the two equal crossings lie side by
    /// side (the twin rule of `transmittance` counts them once), and the order is the
    /// same whatever the order pushed, inline or spilled to the heap.
    #[test]
    fn equal_crossings_sort_side_by_side_whatever_the_order_met() {
        let (a, b) = (
            (0.5, 3, Vec2::new(0.25, 0.5)),
            (0.5, 1, Vec2::new(0.75, 0.0)),
        );
        let far = (0.9, 2, Vec2::ZERO);
        let sorted = |met: &[Crossing]| {
            let mut c = Crossings::default();
            for &m in met {
                c.push(m);
            }
            c.sorted().to_vec()
        };
        let want = vec![b, a, a, far];
        assert_eq!(sorted(&[a, b, a, far]), want);
        assert_eq!(sorted(&[far, a, a, b]), want);
        // Past the inline slots: nine crossings before these four.
        let early: Vec<Crossing> = (0..9)
            .map(|i| (0.01 * (i + 1) as f32, 0, Vec2::ZERO))
            .collect();
        let mut met = early.clone();
        met.extend([a, b, a, far]);
        let mut want_all = early;
        want_all.extend(&want);
        assert_eq!(sorted(&met), want_all);
    }
}
