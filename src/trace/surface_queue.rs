//! The shading points of a depth level, kept in blocks of [`LANES`] consecutive rays
//! with their fields side by side (SoA): the packet path builds them in lanes
//! (`surface_lanes.rs`) and the shading lanes (`shade_lanes.rs`) read them as vectors,
//! where a queue of `Option<Surface>` was written one ray at a time and read back one
//! lane at a time (each vector load waiting on eight scalar stores). The scalar paths
//! (debug, spawned rays, the other models) read and write single entries.

use std::fmt;

use glam::{Vec2, Vec3};

use super::lane_models::LANES;
use super::surface::Surface;
use super::surface_lanes::SurfaceLanes;

/// The shading points of [`LANES`] consecutive rays: lane `j` is ray `j`'s when bit `j`
/// of `hit` is set (other lanes hold leftovers, never read).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct SurfaceBlock {
    /// Position, error bound, normals and texture coordinate, one ray per lane.
    pub(super) lanes: SurfaceLanes,
    /// Material index of each lane.
    pub(super) material: [u32; LANES],
    /// Bit `j` set: ray `j` has a hit.
    pub(super) hit: u32,
}

impl SurfaceBlock {
    /// Lane `j`'s shading point, `None` for a miss.
    pub(super) fn get(&self, j: usize) -> Option<Surface> {
        if self.hit & (1 << j) == 0 {
            return None;
        }
        let s = &self.lanes;
        let lane3 = |v: &[[f32; LANES]; 3]| Vec3::new(v[0][j], v[1][j], v[2][j]);
        Some(Surface {
            p: lane3(&s.p),
            p_error: lane3(&s.p_error),
            ng: lane3(&s.ng),
            n: lane3(&s.n),
            uv: Vec2::new(s.uv[0][j], s.uv[1][j]),
            material: self.material[j],
        })
    }

    /// Makes lane `j` hold `surface` (a miss for `None`).
    pub(super) fn set(&mut self, j: usize, surface: Option<Surface>) {
        let Some(surface) = surface else {
            self.hit &= !(1 << j);
            return;
        };
        let s = &mut self.lanes;
        for a in 0..3 {
            s.p[a][j] = surface.p[a];
            s.p_error[a][j] = surface.p_error[a];
            s.ng[a][j] = surface.ng[a];
            s.n[a][j] = surface.n[a];
        }
        s.uv[0][j] = surface.uv.x;
        s.uv[1][j] = surface.uv.y;
        self.material[j] = surface.material;
        self.hit |= 1 << j;
    }
}

/// Each ray's closest hit as its shading point (`None` for a miss), in queue order,
/// stored in blocks of `LANES` (8) rays. No hit bit of the queue's blocks is set at or
/// past `len`.
#[derive(Clone, Default)]
pub struct SurfaceQueue {
    /// The queue's blocks, then blocks kept from a longer queue before (not entries).
    blocks: Vec<SurfaceBlock>,
    len: usize,
}

impl SurfaceQueue {
    /// Number of entries (rays).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the queue has no entry.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Entry `i`: ray `i`'s shading point, `None` for a miss.
    pub fn get(&self, i: usize) -> Option<Surface> {
        assert!(i < self.len, "entry {i} of {}", self.len);
        self.blocks[i / LANES].get(i % LANES)
    }

    /// Sets entry `i`.
    pub fn set(&mut self, i: usize, surface: Option<Surface>) {
        assert!(i < self.len, "entry {i} of {}", self.len);
        self.blocks[i / LANES].set(i % LANES, surface);
    }

    /// Appends an entry.
    pub fn push(&mut self, surface: Option<Surface>) {
        self.resize(self.len + 1);
        self.set(self.len - 1, surface);
    }

    /// Every entry in order.
    pub fn iter(&self) -> impl Iterator<Item = Option<Surface>> + '_ {
        (0..self.len).map(|i| self.get(i))
    }

    /// Number of entries with a hit.
    pub fn hit_count(&self) -> usize {
        self.blocks()
            .iter()
            .map(|b| b.hit.count_ones() as usize)
            .sum()
    }

    /// Makes the queue `len` entries long; new entries are misses. The blocks are kept
    /// when it shrinks and taken up again when it grows, only their hit bits cleared: a
    /// render's queue shrinks to its reflection rays at depth 1 and grows back to every
    /// camera ray at the next pass, where a `Vec` cut and grown again zeroed every block
    /// (about 480 bytes per 8 rays: 16 MB per pass at 512×512).
    pub fn resize(&mut self, len: usize) {
        let (old, new) = (self.len.div_ceil(LANES), len.div_ceil(LANES));
        if new > self.blocks.len() {
            self.blocks.resize_with(new, SurfaceBlock::default);
        }
        // Blocks taken up again hold an earlier queue's entries: misses now (their
        // lanes' other fields are leftovers, never read).
        for block in &mut self.blocks[old.min(new)..new] {
            block.hit = 0;
        }
        self.len = len;
        if !len.is_multiple_of(LANES) {
            self.blocks[new - 1].hit &= (1 << (len % LANES)) - 1;
        }
    }

    /// The blocks: block `b` holds entries `b * LANES ..`.
    pub(super) fn blocks(&self) -> &[SurfaceBlock] {
        &self.blocks[..self.len.div_ceil(LANES)]
    }

    /// The blocks, to be written; a block's hit bits past `len` must stay clear.
    pub(super) fn blocks_mut(&mut self) -> &mut [SurfaceBlock] {
        let n = self.len.div_ceil(LANES);
        &mut self.blocks[..n]
    }
}

impl FromIterator<Option<Surface>> for SurfaceQueue {
    fn from_iter<I: IntoIterator<Item = Option<Surface>>>(iter: I) -> Self {
        let mut queue = SurfaceQueue::default();
        for surface in iter {
            queue.push(surface);
        }
        queue
    }
}

impl From<Vec<Option<Surface>>> for SurfaceQueue {
    fn from(surfaces: Vec<Option<Surface>>) -> Self {
        surfaces.into_iter().collect()
    }
}

/// Entries compare, not what the blocks hold in lanes without a hit.
impl PartialEq for SurfaceQueue {
    fn eq(&self, other: &Self) -> bool {
        self.len == other.len && self.iter().eq(other.iter())
    }
}

impl fmt::Debug for SurfaceQueue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface(x: f32, material: u32) -> Surface {
        Surface {
            p: Vec3::new(x, -x, 0.5),
            p_error: Vec3::splat(x * 1e-7),
            ng: Vec3::Y,
            n: Vec3::new(0.6, 0.8, 0.0),
            uv: Vec2::new(x, 0.25),
            material,
        }
    }

    #[test]
    fn entries_read_back_as_written_across_blocks() {
        let entries: Vec<Option<Surface>> = (0..3 * LANES + 5)
            .map(|i| (i % 3 != 1).then(|| surface(i as f32, i as u32)))
            .collect();
        let queue = SurfaceQueue::from(entries.clone());
        assert_eq!(queue.len(), entries.len());
        assert_eq!(queue.iter().collect::<Vec<_>>(), entries);
        assert_eq!(
            queue.hit_count(),
            entries.iter().filter(|e| e.is_some()).count()
        );
        assert_eq!(queue.blocks().len(), 4);
    }

    #[test]
    fn shrinking_drops_the_hits_past_the_end() {
        let mut queue: SurfaceQueue = (0..2 * LANES)
            .map(|i| Some(surface(1.0, i as u32)))
            .collect();
        queue.resize(LANES + 3);
        assert_eq!(queue.hit_count(), LANES + 3);
        // Grown again, the entries past the old end are misses, not the old hits.
        queue.resize(2 * LANES);
        assert_eq!(queue.get(LANES + 2), Some(surface(1.0, LANES as u32 + 2)));
        assert_eq!(queue.get(LANES + 3), None);
        assert_eq!(queue.hit_count(), LANES + 3);
        queue.set(0, None);
        assert_eq!(queue.get(0), None);
        assert_eq!(queue.hit_count(), LANES + 2);
    }

    #[test]
    fn blocks_kept_past_the_end_come_back_as_misses() {
        let mut queue: SurfaceQueue = (0..4 * LANES)
            .map(|i| Some(surface(2.0, i as u32)))
            .collect();
        // Shrunk by whole blocks: they are kept, but are not entries.
        queue.resize(LANES - 2);
        assert_eq!(queue.blocks.len(), 4);
        assert_eq!(queue.blocks().len(), 1);
        assert_eq!(queue.hit_count(), LANES - 2);
        // Grown again past them: every entry from the old end on is a miss.
        queue.resize(3 * LANES + 1);
        assert_eq!(queue.blocks().len(), 4);
        assert_eq!(queue.hit_count(), LANES - 2);
        assert_eq!(queue.get(LANES - 3), Some(surface(2.0, LANES as u32 - 3)));
        assert!((LANES - 2..3 * LANES + 1).all(|i| queue.get(i).is_none()));
        // Past the storage: new blocks.
        queue.resize(6 * LANES);
        assert_eq!(queue.blocks().len(), 6);
        assert_eq!(queue.hit_count(), LANES - 2);
        queue.set(6 * LANES - 1, Some(surface(3.0, 7)));
        assert_eq!(queue.hit_count(), LANES - 1);
        queue.resize(0);
        assert_eq!((queue.blocks().len(), queue.hit_count()), (0, 0));
    }
}
