//! Tests of the collapse's choice of nodes and leaves (`wide_collapse`), with the
//! helpers of the wide BVH's tests.

use super::*;
use crate::accel::leaf::TriGroup;

/// The collapse before the costed one: each node takes the largest-area interior
/// children in place of their parents until it has `WIDTH`; leaves are the binary
/// tree's. Leaf lanes hold their binary `(slot, count)`.
fn greedy_collapse(bvh: &Bvh, b: usize, out: &mut Vec<WideNode>) -> u32 {
    let me = out.len();
    out.push(WideNode::UNUSED);
    let first = &bvh.nodes[b];
    let mut kids: Vec<usize> = if first.is_leaf() {
        vec![b]
    } else {
        vec![b + 1, first.offset as usize]
    };
    while kids.len() < WIDTH {
        let Some(k) = (0..kids.len())
            .filter(|&k| !bvh.nodes[kids[k]].is_leaf())
            .max_by(|&x, &y| {
                let area = |k: usize| bvh.nodes[kids[k]].bounds().surface_area();
                area(x).total_cmp(&area(y))
            })
        else {
            break;
        };
        let open = kids[k];
        kids[k] = open + 1;
        kids.insert(k + 1, bvh.nodes[open].offset as usize);
    }
    for (lane, &k) in kids.iter().enumerate() {
        let node = &bvh.nodes[k];
        out[me].set_child_bounds(lane, node.bounds());
        out[me].child[lane] = if node.is_leaf() {
            out[me].count[lane] = node.count;
            node.offset
        } else {
            greedy_collapse(bvh, k, out)
        };
    }
    me as u32
}

/// The collapse's cost of `nodes` (leaf lanes holding their triangle count) under a
/// root of area `root`, summed lane by lane: `NODE_COST` times the area of each node,
/// `leaf_cost` of each leaf.
fn tree_cost(nodes: &[WideNode], root: f32) -> f64 {
    use crate::accel::wide_collapse::{NODE_COST, leaf_cost};
    let mut cost = (NODE_COST * root) as f64;
    for node in nodes {
        for lane in 0..WIDTH {
            let area = node.child_bounds(lane).surface_area();
            match (node.child[lane], node.count[lane]) {
                (EMPTY, _) => {}
                (_, 0) => cost += (NODE_COST * area) as f64,
                (_, count) => cost += leaf_cost(area, count) as f64,
            }
        }
    }
    cost
}

fn costed_collapse(bvh: &Bvh) -> Vec<WideNode> {
    let mut nodes = HugeVec::new();
    crate::accel::wide_collapse::collapse(bvh, &mut nodes, &mut |slot, count| (slot, count));
    nodes.to_vec()
}

#[test]
fn the_collapse_costs_less_than_the_greedy_one_in_fewer_nodes() {
    // The costed collapse chooses among all trees the greedy one could make (and
    // more), so it never costs more; the greedy one left its lower nodes half empty.
    // The SAH grid's leaves fill its nodes already: no gain there.
    for (tris, split, gain) in [
        (random_tris(3000, 13), SplitMethod::SahBinned, true),
        (random_tris(3000, 14), SplitMethod::Median, true),
        (grid(24), SplitMethod::SahBinned, false),
        (grid(16), SplitMethod::Median, true),
    ] {
        let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
        let bvh = Bvh::build(&bounds, split);
        let costed = costed_collapse(&bvh);
        let mut greedy = Vec::new();
        greedy_collapse(&bvh, 0, &mut greedy);
        let root = bvh.nodes[0].bounds().surface_area();
        let (c, g) = (tree_cost(&costed, root), tree_cost(&greedy, root));
        assert!(c <= g * (1.0 + 1e-5), "{c} > {g}");
        if gain {
            assert!(c < 0.95 * g, "{c} for {g}: no gain");
            let (c, g) = (costed.len(), greedy.len());
            assert!(2 * c < g, "{c} nodes for {g}");
        }
        // The tree built is the one whose cost the collapse found least (summed in
        // another order).
        let least = crate::accel::wide_collapse::least_cost(&bvh) as f64;
        assert!(
            (c - least).abs() <= 1e-5 * least,
            "{c} built, {least} found"
        );
    }
}

/// The leaf groups as `LeafTris::build` made them before the collapse grouped leaves as
/// it met them: every leaf lane of the collapsed nodes (holding binary slots), sorted by
/// slot, then grouped.
fn reference_leaves(bvh: &Bvh, tris: &[Tri]) -> (Vec<WideNode>, LeafTris) {
    let mut nodes = costed_collapse(bvh);
    let mut lanes = Vec::new();
    for (i, node) in nodes.iter().enumerate() {
        for lane in 0..WIDTH {
            if node.count[lane] > 0 {
                lanes.push((node.child[lane], i, lane));
            }
        }
    }
    lanes.sort_unstable();
    let mut groups = Vec::new();
    for (slot, i, lane) in lanes {
        let count = nodes[i].count[lane];
        let first = groups.len();
        groups.resize(first + groups_for(count as usize), TriGroup::PADDING);
        (nodes[i].child[lane], nodes[i].count[lane]) =
            push_leaf(&mut groups, first, slot, count, &bvh.prim_indices, tris);
    }
    let groups = groups.into();
    (nodes, LeafTris { groups })
}

#[test]
fn the_collapse_groups_leaves_in_slot_order() {
    for (tris, split) in sample_trees(1, 3000, 15, 24) {
        let (bvh, wide) = both(&tris, split);
        let (nodes, leaves) = reference_leaves(&bvh, &tris);
        assert_eq!(wide.nodes, nodes);
        assert!(wide.leaves.prims().eq(leaves.prims()));
        let bits = |l: &LeafTris| -> Vec<u32> {
            let v = l
                .groups
                .iter()
                .flat_map(|g| g.v.as_flattened().as_flattened());
            v.map(|x| x.to_bits()).collect()
        };
        assert_eq!(bits(&wide.leaves), bits(&leaves));
    }
}

/// Wide leaf lanes of `wide` that hold more than one binary leaf of `bvh`.
fn merged_leaves(bvh: &Bvh, wide: &WideBvh) -> usize {
    let leaf_lanes = wide.nodes.iter().flat_map(|n| n.count).filter(|&c| c > 0);
    bvh.leaf_count() - leaf_lanes.count()
}

#[test]
fn merged_leaves_hold_their_triangles_and_answer_as_the_binary_tree() {
    // Subtrees of a few triangles merged into one leaf, whose box must hold every one
    // of them (validate), and whose answers are still the binary tree's.
    for (tris, seed) in [(random_tris(3000, 21), 22), (random_tris(3000, 13), 23)] {
        let (bvh, wide) = both(&tris, SplitMethod::SahBinned);
        assert!(
            merged_leaves(&bvh, &wide) >= 3,
            "{}",
            merged_leaves(&bvh, &wide)
        );
        wide.validate(&tris).unwrap();
        for (ray, t_max) in rays(2000, seed) {
            let expect = binary_closest(&bvh, &tris, &ray, t_max);
            let got = wide.closest_hit(&ray, t_max).map(|(p, h)| (p, h.t));
            assert_eq!(got, expect, "{ray:?}");
            let any = wide.any_hit(&ray, t_max, |_, _| true);
            assert_eq!(any, expect.is_some(), "{ray:?}");
        }
    }
}

#[test]
fn sibling_leaves_that_fit_one_group_share_it() {
    // Four triangles in one spot that the binary tree splits into leaves of 1 and 3,
    // and four far away in one leaf: the first four become one leaf of one group (its
    // box both leaves'), not two groups of which one holds three padding lanes.
    let at = |x: f32| -> Tri {
        [
            vec3(x, 0.0, 0.0),
            vec3(x + 1.0, 0.0, 0.0),
            vec3(x, 1.0, 0.0),
        ]
    };
    let tris: Vec<Tri> = [0.0, 0.01, 0.02, 0.03, 10.0, 10.01, 10.02, 10.03]
        .into_iter()
        .map(at)
        .collect();
    let bound = |r: std::ops::Range<usize>| {
        let boxes = tris[r].iter().map(|t| Aabb::from_points(t));
        boxes.reduce(Aabb::union).unwrap()
    };
    let bvh = Bvh {
        nodes: vec![
            BvhNode::interior(bound(0..8), 4),
            BvhNode::interior(bound(0..4), 3),
            BvhNode::leaf(bound(0..1), 0, 1),
            BvhNode::leaf(bound(1..4), 1, 3),
            BvhNode::leaf(bound(4..8), 4, 4),
        ]
        .into(),
        prim_indices: (0..8).collect::<Vec<u32>>().into(),
    };
    let wide = WideBvh::collapse(&bvh, &tris);
    wide.validate(&tris).unwrap();
    assert_eq!((wide.nodes.len(), wide.leaves.groups.len()), (1, 2));
    let root = &wide.nodes[0];
    assert_eq!(&root.count[..3], &[4, 4, 0]);
    assert_eq!(root.child_bounds(0), bound(0..4));
    assert_eq!(root.child_bounds(1), bound(4..8));
    assert!(wide.leaves.prims().eq(0..8));
}

/// The two triangles of the parallelogram `origin + [0, 1] u + [0, 1] v`.
fn wall(origin: Vec3, u: Vec3, v: Vec3) -> [Tri; 2] {
    [
        [origin, origin + u, origin + u + v],
        [origin, origin + u + v, origin + v],
    ]
}

/// Floor, ceiling, back and right walls of the Cornell box (the 8 triangles of the
/// leaf the SAH made of them), and a short block standing in it.
fn room() -> Vec<Tri> {
    let (x, y, z) = (
        vec3(2.0, 0.0, 0.0),
        vec3(0.0, 2.0, 0.0),
        vec3(0.0, 0.0, 2.0),
    );
    let mut tris: Vec<Tri> = [
        wall(vec3(-1.0, 0.0, 1.0), x, -z),
        wall(vec3(-1.0, 2.0, -1.0), x, z),
        wall(vec3(-1.0, 0.0, -1.0), x, y),
        wall(vec3(1.0, 0.0, -1.0), z, y),
    ]
    .concat();
    // A tilted slab (boxes not flat), far from the walls' planes.
    for i in 0..6 {
        let o = vec3(-0.5 + 0.1 * i as f32, 0.3, 0.2);
        tris.push([o, o + vec3(0.3, 0.1, 0.05), o + vec3(0.05, 0.4, 0.2)]);
    }
    tris
}

#[test]
fn the_walls_of_a_room_keep_a_flat_leaf_each() {
    // Rays from inside the room meet a leaf whose box is the room's always, and a
    // wall's flat box only where they cross it: the build splits the walls apart and
    // the collapse does not merge them back (`build/rooms.rs`, `encloses`).
    // Beside many triangles far off, the room is a subtree the collapse could merge.
    let far = random_tris(500, 33)
        .into_iter()
        .map(|t| t.map(|v| v + Vec3::splat(30.0)));
    let with_far = room()[..8].iter().copied().chain(far).collect();
    for tris in [room(), room()[..8].to_vec(), room()[..4].to_vec(), with_far] {
        let (bvh, wide) = both(&tris, SplitMethod::SahBinned);
        let mut walls = 0;
        for node in &wide.nodes {
            for l in 0..WIDTH {
                let (lo, hi) = (
                    vec3(node.bounds[0][l], node.bounds[1][l], node.bounds[2][l]),
                    vec3(node.bounds[3][l], node.bounds[4][l], node.bounds[5][l]),
                );
                if node.child[l] == u32::MAX
                    || node.count[l] == 0
                    || lo.cmpge(vec3(-0.9, 0.1, -0.9)).all()
                {
                    continue;
                }
                // A leaf lane reaching a wall: exactly that wall's two triangles.
                walls += 1;
                assert_eq!(node.count[l], 2, "{lo} {hi}");
                assert!((hi - lo).min_element() == 0.0, "{lo} {hi}");
            }
        }
        assert_eq!(walls, tris.len().min(8) / 2, "{} triangles", tris.len());
        wide.validate(&tris).unwrap();
        // Rays from anywhere, and from inside the room.
        let mut rng = Lcg(32);
        let inside = (0..1000).map(|_| {
            let o = rng.vec() * 1.9 + vec3(-0.95, 0.05, -0.95);
            (
                Ray::new(o, rng.dir()),
                if rng.below(2) == 0 {
                    1.0
                } else {
                    f32::INFINITY
                },
            )
        });
        for (ray, t_max) in rays(2000, 31).into_iter().chain(inside) {
            let expect = binary_closest(&bvh, &tris, &ray, t_max);
            let got = wide.closest_hit(&ray, t_max).map(|(p, h)| (p, h.t));
            assert_eq!(got, expect, "{ray:?}");
            assert_eq!(wide.any_hit(&ray, t_max, |_, _| true), expect.is_some());
        }
    }
}

#[test]
fn the_tree_hash_tells_trees_apart_by_any_node_or_leaf_byte() {
    let tris = random_tris(3000, 21);
    let (bvh, wide) = both(&tris, SplitMethod::SahBinned);
    let again = WideBvh::collapse(&bvh, &tris);
    assert_eq!(wide.tree_hash(), again.tree_hash());
    let mut moved = again.clone();
    moved.nodes.modify(|n| n[0].bounds[4][0] += 1e-3);
    assert_ne!(moved.tree_hash(), wide.tree_hash());
    let mut moved = again;
    moved.leaves.groups.modify(|g| {
        let last = g.len() - 1;
        bytemuck::bytes_of_mut(&mut g[last])[0] ^= 1;
    });
    assert_ne!(moved.tree_hash(), wide.tree_hash());
}
