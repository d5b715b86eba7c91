//! Tests of the room split: it splits walls by plane and leaves closed meshes alone.

use glam::{Vec3, vec3};

use super::super::{NodeBounds, PrimRef};
use super::*;
use crate::accel::Aabb;
use crate::accel::bvh::{Bvh, SplitMethod};
use crate::test_util::{Mesh, icosphere};

fn refs_of(boxes: &[Aabb]) -> Vec<PrimRef> {
    boxes
        .iter()
        .enumerate()
        .map(|(i, b)| PrimRef::new(i, b))
        .collect()
}

fn boxes(mesh: &Mesh) -> Vec<Aabb> {
    (0..mesh.tris.len())
        .map(|i| {
            let (a, b, c) = mesh.tri(i);
            Aabb::from_points(&[a, b, c])
        })
        .collect()
}

#[test]
fn walls_in_different_planes_split_by_plane() {
    // A floor's two triangles and a back wall's, interleaved: the first plane's
    // primitives first, in their order, then the rest.
    let floor = Aabb::new(vec3(-1.0, 0.0, -1.0), vec3(1.0, 0.0, 1.0));
    let back = Aabb::new(vec3(-1.0, 0.0, -1.0), vec3(1.0, 2.0, -1.0));
    let mut refs = refs_of(&[back, floor, back, floor]);
    let b = NodeBounds::of(&refs);
    let (mid, left, right) = split_room(&mut refs, &b).expect("a room");
    assert_eq!(mid, 2);
    let order: Vec<u32> = refs.iter().map(PrimRef::index).collect();
    assert_eq!(order, [0, 2, 1, 3]);
    assert!(!has_volume(&left.node) && !has_volume(&right.node));
    // One plane (a flat node) or a primitive that is not flat: no split.
    assert!(split_room(&mut refs[..2], &left).is_none());
    let mut refs = refs_of(&[back, floor, Aabb::new(Vec3::ZERO, Vec3::ONE)]);
    let b = NodeBounds::of(&refs);
    assert!(split_room(&mut refs, &b).is_none());
}

#[test]
fn closed_meshes_have_no_rooms() {
    // The leaves of a sphere are not rooms, so its tree is the SAH's: no leaf holds
    // primitives the rule would split.
    let boxes = boxes(&icosphere(4));
    let bvh = Bvh::build(&boxes, SplitMethod::SahBinned);
    for n in bvh.nodes.iter().filter(|n| n.is_leaf()) {
        let slots = n.offset as usize..(n.offset + n.count) as usize;
        let leaf: Vec<Aabb> = bvh.prim_indices[slots]
            .iter()
            .map(|&p| boxes[p as usize])
            .collect();
        let mut refs = refs_of(&leaf);
        let b = NodeBounds::of(&refs);
        assert!(split_room(&mut refs, &b).is_none());
    }
}
