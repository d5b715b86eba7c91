//! The split of "rooms": small nodes whose primitives are flat boxes lying in at least
//! two axis planes, around empty space (the walls, floor and ceiling of a room, a
//! corner of a floor and a wall), which the SAH keeps as one leaf.
//!
//! The SAH's odds of a ray meeting a box grow with its area, which holds for rays from
//! outside the box. Rays that start inside a box meet it always (Fabianowski, Fowler,
//! Dingliana 2009, "A Cost Metric for Scene-Interior Ray Origins"), and rays start
//! inside a room's box: from every surface in the room. In the Cornell box one leaf of
//! four walls (8 triangles, its box the whole room) took 9.8 of the ~12 triangle
//! prefilters per shadow packet and occluded none of them: a shadow ray runs between
//! two points inside the room, so it crosses no wall, and a ray that leaves the room
//! crosses one. Apart, each plane's triangles get a flat box, which such a ray meets
//! only where it crosses that plane. No binary split of two or more walls shrinks their
//! box (any two walls of a room span it), so the SAH, which compares a split with the
//! leaf one level at a time, never starts one; this rule splits by plane until each
//! part is one plane (a flat leaf), and the collapse keeps the parts apart
//! (`wide_collapse::encloses`).
//!
//! Closed meshes are untouched: their triangles' boxes are not flat (only triangles in
//! an axis plane are), and a leaf of coplanar triangles is flat itself.

use super::{Box4, NodeBounds, PrimRef};

/// The axis plane `r`'s box lies in, `(axis, coordinate)`: its first axis of zero
/// extent (NaN has none).
#[inline(always)]
fn plane_of(r: &PrimRef) -> Option<(usize, f32)> {
    let hi = r.hi();
    (0..3).find(|&a| r.lo[a] == hi[a]).map(|a| (a, r.lo[a]))
}

/// Whether box `b` has volume: it is not flat (nor empty, nor NaN).
pub(super) fn has_volume(b: &Box4) -> bool {
    (0..3).all(|a| b.max[a] > b.min[a])
}

/// For a node that would be a leaf: when all its primitives are flat in axis planes
/// and its box has volume (so there are at least two planes), moves the primitives in
/// the first primitive's plane first and returns their count with both parts' bounds;
/// else None, and `refs` is untouched. Inlined into the build's `split`: nearly every
/// leaf of a closed mesh leaves at its first primitive, which is not flat.
#[inline(always)]
pub(super) fn split_room(
    refs: &mut [PrimRef],
    b: &NodeBounds,
) -> Option<(usize, NodeBounds, NodeBounds)> {
    let first = plane_of(refs.first()?)?;
    if refs.len() < 2 || !has_volume(&b.node) {
        return None;
    }
    split_by_plane(refs, first)
}

/// [`split_room`] past its first primitive: the rest are flat too, or None.
#[inline(never)]
fn split_by_plane(
    refs: &mut [PrimRef],
    first: (usize, f32),
) -> Option<(usize, NodeBounds, NodeBounds)> {
    for r in refs.iter() {
        plane_of(r)?;
    }
    // Stable, so each part keeps the build's order; at most `MAX_LEAF` primitives.
    refs.sort_by_key(|r| plane_of(r) != Some(first));
    let mid = refs
        .iter()
        .take_while(|r| plane_of(r) == Some(first))
        .count();
    let (left, right) = refs.split_at(mid);
    Some((mid, NodeBounds::of(left), NodeBounds::of(right)))
}

#[cfg(test)]
#[path = "rooms_tests.rs"]
mod tests;
