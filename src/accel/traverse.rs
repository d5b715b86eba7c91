//! Stack-based BVH traversal: ordered closest-hit and unordered any-hit, as in
//! Pharr, Jakob and Humphreys, *Physically Based Rendering* (3rd ed.), §4.4.3
//! "Traversal", with the robust slab test of Ize 2013 (see [`super::aabb`]).
//!
//! The stack is a fixed array on the call stack and the inverse direction is
//! computed once per ray: no heap allocation per ray.

use super::Ray;
use super::bvh::{Bvh, MAX_DEPTH};

/// Observes a traversal (for statistics and the visual debug); default methods do nothing.
pub trait TraversalVisitor {
    /// Called for every node whose box the ray enters, with its depth (root = 0).
    fn visit_node(&mut self, _node: u32, _depth: u32) {}
    /// Called before every primitive test.
    fn test_prim(&mut self, _prim: u32) {}
}

impl TraversalVisitor for () {}

/// Counts visited nodes and tested primitives.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Nodes whose boxes the ray entered.
    pub nodes_visited: u64,
    /// Primitive tests performed.
    pub prims_tested: u64,
}

impl TraversalVisitor for TraversalStats {
    fn visit_node(&mut self, _node: u32, _depth: u32) {
        self.nodes_visited += 1;
    }
    fn test_prim(&mut self, _prim: u32) {
        self.prims_tested += 1;
    }
}

/// Traversal stack entry: a node to visit, its depth and its box entry distance.
#[derive(Clone, Copy, Default)]
struct Entry {
    node: u32,
    depth: u32,
    t_entry: f32,
}

const STACK_SIZE: usize = MAX_DEPTH as usize;

impl Bvh {
    /// Closest hit: `hit(prim, t_max)` returns Some(t) for a hit closer than t_max. Returns the closest (prim, t).
    pub fn closest_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        visitor: &mut impl TraversalVisitor,
        mut hit: impl FnMut(u32, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        let root = self.nodes.first()?;
        let inv_dir = ray.dir.recip();
        let origin = ray.origin;
        let mut best_t = t_max;
        let mut best = None;
        let Some(t_root) = root.bounds().intersect_ray(origin, inv_dir, best_t) else {
            return None;
        };
        let mut stack = [Entry::default(); STACK_SIZE];
        let mut sp = 0;
        let mut cur = Entry {
            node: 0,
            depth: 0,
            t_entry: t_root,
        };
        loop {
            // A box pushed earlier may now lie beyond the closest hit found since.
            if cur.t_entry <= best_t {
                visitor.visit_node(cur.node, cur.depth);
                let node = &self.nodes[cur.node as usize];
                if node.is_leaf() {
                    for k in node.offset..node.offset + node.count {
                        let prim = self.prim_indices[k as usize];
                        visitor.test_prim(prim);
                        if let Some(t) = hit(prim, best_t) {
                            if t < best_t {
                                best_t = t;
                                best = Some((prim, t));
                            }
                        }
                    }
                } else {
                    let (a, b) = (cur.node + 1, node.offset);
                    let ta = self.nodes[a as usize]
                        .bounds()
                        .intersect_ray(origin, inv_dir, best_t);
                    let tb = self.nodes[b as usize]
                        .bounds()
                        .intersect_ray(origin, inv_dir, best_t);
                    let depth = cur.depth + 1;
                    let next = match (ta, tb) {
                        (Some(ta), Some(tb)) => {
                            // Visit the nearer child now, the farther one later.
                            let (near, far) = if tb < ta {
                                ((b, tb), (a, ta))
                            } else {
                                ((a, ta), (b, tb))
                            };
                            stack[sp] = Entry {
                                node: far.0,
                                depth,
                                t_entry: far.1,
                            };
                            sp += 1;
                            Some(near)
                        }
                        (Some(ta), None) => Some((a, ta)),
                        (None, Some(tb)) => Some((b, tb)),
                        (None, None) => None,
                    };
                    if let Some((node, t_entry)) = next {
                        cur = Entry {
                            node,
                            depth,
                            t_entry,
                        };
                        continue;
                    }
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            cur = stack[sp];
        }
        best
    }

    /// Visits primitives whose boxes the ray meets in (0, t_max) until `visit(prim)` returns true (stop). Returns whether it stopped. Used both for binary shadows (stop at first hit) and transparent shadows (multiply tints, stop at an opaque one).
    pub fn any_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        visitor: &mut impl TraversalVisitor,
        mut visit: impl FnMut(u32) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let inv_dir = ray.dir.recip();
        let origin = ray.origin;
        // (node, depth); boxes are tested when popped, no ordering needed.
        let mut stack = [(0u32, 0u32); STACK_SIZE + 1];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (i, depth) = stack[sp];
            let node = &self.nodes[i as usize];
            if node
                .bounds()
                .intersect_ray(origin, inv_dir, t_max)
                .is_none()
            {
                continue;
            }
            visitor.visit_node(i, depth);
            if node.is_leaf() {
                for k in node.offset..node.offset + node.count {
                    let prim = self.prim_indices[k as usize];
                    visitor.test_prim(prim);
                    if visit(prim) {
                        return true;
                    }
                }
            } else {
                // Second child below the first so the first is visited first.
                stack[sp] = (node.offset, depth + 1);
                stack[sp + 1] = (i + 1, depth + 1);
                sp += 2;
            }
        }
        false
    }
}
