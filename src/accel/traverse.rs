//! Stack-based BVH traversal: ordered closest-hit and unordered any-hit, as in
//! Pharr, Jakob and Humphreys, *Physically Based Rendering* (3rd ed.), §4.4.3
//! "Traversal", with the robust slab test of Ize 2013 (see [`super::aabb`]).
//!
//! The stack is a fixed array on the call stack and the inverse direction is
//! computed once per ray: no heap allocation per ray.

use super::bvh::{Bvh, MAX_DEPTH};
use super::{BOX_MARGIN, Ray};

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
    /// Closest hit: `hit(prim, t_max)` returns Some(t) for a hit closer than t_max. Returns the closest (prim, t); of equally close ones, the lowest prim.
    pub fn closest_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        visitor: &mut impl TraversalVisitor,
        mut hit: impl FnMut(u32, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        // Plain slices: each of a `HugeVec`'s accesses would look at its backing.
        let (nodes, prims) = (self.nodes.as_slice(), self.prim_indices.as_slice());
        let root = nodes.first()?;
        let inv_dir = ray.dir.recip();
        let origin = ray.origin;
        let mut best_t = t_max;
        let mut best = None;
        let t_root = root.bounds().intersect_ray(origin, inv_dir, best_t)?;
        let mut stack = [Entry::default(); STACK_SIZE];
        let mut sp = 0;
        let mut cur = Entry {
            node: 0,
            depth: 0,
            t_entry: t_root,
        };
        loop {
            // A box pushed earlier may now lie beyond the closest hit found since. With
            // the slab test's margin, as in the wide BVH: a box entry rounded just past a
            // hit on its face must not hide a tie there.
            if cur.t_entry <= best_t * BOX_MARGIN {
                visitor.visit_node(cur.node, cur.depth);
                let node = &nodes[cur.node as usize];
                if node.is_leaf() {
                    for k in node.offset..node.offset + node.count {
                        let prim = prims[k as usize];
                        visitor.test_prim(prim);
                        // A few ulps past the best t so far (the rounding of the
                        // triangle test's scaled early-out), so every primitive at the
                        // best t passes the test and the comparison below decides: of
                        // primitives hit at exactly the same t (where two meet), the
                        // lowest index wins whatever the order of the tree (the wide
                        // BVH agrees).
                        let bound = if best.is_some() {
                            best_t.next_up().next_up().next_up().min(t_max)
                        } else {
                            best_t
                        };
                        if let Some(t) = hit(prim, bound)
                            && best.is_none_or(|(bp, bt)| t < bt || (t == bt && prim < bp))
                        {
                            best_t = t;
                            best = Some((prim, t));
                        }
                    }
                } else {
                    let (a, b) = (cur.node + 1, node.offset);
                    let ta = nodes[a as usize]
                        .bounds()
                        .intersect_ray(origin, inv_dir, best_t);
                    let tb = nodes[b as usize]
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
        let (nodes, prims) = (self.nodes.as_slice(), self.prim_indices.as_slice());
        let Some(root) = nodes.first() else {
            return false;
        };
        let inv_dir = ray.dir.recip();
        let origin = ray.origin;
        if root
            .bounds()
            .intersect_ray(origin, inv_dir, t_max)
            .is_none()
        {
            return false;
        }
        // Same near-first order as closest_hit: no ordering is required for
        // correctness, but shadow rays leaving a surface are mostly blocked
        // close to their origin, so the near child finds the occluder sooner.
        let mut stack = [(0u32, 0u32); STACK_SIZE];
        let mut sp = 0;
        let mut cur = (0u32, 0u32);
        loop {
            let (i, depth) = cur;
            visitor.visit_node(i, depth);
            let node = &nodes[i as usize];
            if node.is_leaf() {
                for k in node.offset..node.offset + node.count {
                    let prim = prims[k as usize];
                    visitor.test_prim(prim);
                    if visit(prim) {
                        return true;
                    }
                }
            } else {
                let (a, b) = (i + 1, node.offset);
                let ta = nodes[a as usize]
                    .bounds()
                    .intersect_ray(origin, inv_dir, t_max);
                let tb = nodes[b as usize]
                    .bounds()
                    .intersect_ray(origin, inv_dir, t_max);
                let depth = depth + 1;
                let next = match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far) = if tb < ta { (b, a) } else { (a, b) };
                        stack[sp] = (far, depth);
                        sp += 1;
                        Some(near)
                    }
                    (Some(_), None) => Some(a),
                    (None, Some(_)) => Some(b),
                    (None, None) => None,
                };
                if let Some(n) = next {
                    cur = (n, depth);
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            cur = stack[sp];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{Aabb, RayShear, SplitMethod, intersect_triangle_sheared};
    use crate::test_util::Lcg;
    use glam::{Vec3, vec3};

    type Tri = [Vec3; 3];

    fn random_tris(n: usize, seed: u64) -> Vec<Tri> {
        let mut rng = Lcg(seed);
        (0..n)
            .map(|_| {
                let c = rng.vec() * 10.0 - Vec3::splat(5.0);
                [c, c + rng.dir() * 0.5, c + rng.dir() * 0.5]
            })
            .collect()
    }

    fn tri_bounds(tris: &[Tri]) -> Vec<Aabb> {
        tris.iter().map(|t| Aabb::from_points(t)).collect()
    }

    fn random_rays(n: usize, seed: u64) -> Vec<(Ray, f32)> {
        let mut rng = Lcg(seed);
        (0..n)
            .map(|i| {
                let o = rng.vec() * 14.0 - Vec3::splat(7.0);
                let mut d = rng.dir();
                // Some axis-aligned directions, with zero components.
                if i % 10 == 0 {
                    d = Vec3::ZERO;
                    d[i / 10 % 3] = if i % 20 == 0 { 1.0 } else { -1.0 };
                }
                let t_max = if i % 3 == 0 { 4.0 } else { f32::INFINITY };
                // Non-unit lengths too.
                (Ray::new(o, d * (0.5 + rng.next_f32())), t_max)
            })
            .collect()
    }

    fn closest(bvh: &Bvh, tris: &[Tri], ray: &Ray, t_max: f32) -> Option<(u32, f32)> {
        let s = RayShear::new(ray);
        bvh.closest_hit(ray, t_max, &mut (), |p, t| {
            let [a, b, c] = tris[p as usize];
            intersect_triangle_sheared(&s, ray.origin, a, b, c, t).map(|h| h.t)
        })
    }

    #[test]
    fn empty_bvh_never_hits() {
        let b = Bvh::default();
        let r = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(
            b.closest_hit(&r, f32::INFINITY, &mut (), |_, _| Some(1.0)),
            None
        );
        assert!(!b.any_hit(&r, f32::INFINITY, &mut (), |_| true));
    }

    #[test]
    fn closest_hit_matches_brute_force() {
        let tris = random_tris(3000, 21);
        let bounds = tri_bounds(&tris);
        let brute = Bvh::single_leaf(&bounds);
        for m in [SplitMethod::SahBinned, SplitMethod::Median] {
            let bvh = Bvh::build(&bounds, m);
            assert_eq!(bvh.validate(&bounds), Ok(()));
            let mut hits = 0;
            for (ray, t_max) in random_rays(5000, 8) {
                let expect = closest(&brute, &tris, &ray, t_max);
                let got = closest(&bvh, &tris, &ray, t_max);
                assert_eq!(got, expect, "{m:?} {ray:?}");
                hits += got.is_some() as u32;
            }
            // The comparison is meaningful only if many rays hit.
            assert!(hits > 1000, "only {hits} hits");
        }
    }

    #[test]
    fn any_hit_agrees_with_closest_hit() {
        let tris = random_tris(2000, 5);
        let bounds = tri_bounds(&tris);
        let bvh = Bvh::build(&bounds, SplitMethod::SahBinned);
        for (ray, t_max) in random_rays(5000, 13) {
            let s = RayShear::new(&ray);
            let test = |p: u32| {
                let [a, b, c] = tris[p as usize];
                intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max).is_some()
            };
            let occluded = bvh.any_hit(&ray, t_max, &mut (), test);
            assert_eq!(occluded, closest(&bvh, &tris, &ray, t_max).is_some());

            // Without stopping, every hit primitive is visited exactly once.
            let mut seen = Vec::new();
            let stopped = bvh.any_hit(&ray, t_max, &mut (), |p| {
                if test(p) {
                    seen.push(p);
                }
                false
            });
            assert!(!stopped);
            seen.sort();
            let all: Vec<u32> = (0..tris.len() as u32).filter(|&p| test(p)).collect();
            assert_eq!(seen, all);
        }
    }

    #[test]
    fn stats_count_work() {
        let tris = random_tris(100, 2);
        let bounds = tri_bounds(&tris);
        let ray = Ray::new(Vec3::splat(-10.0), Vec3::ONE);
        // Brute force: the root box is entered once and every triangle tested.
        let mut st = TraversalStats::default();
        Bvh::single_leaf(&bounds).closest_hit(&ray, f32::INFINITY, &mut st, |_, _| None);
        assert_eq!(
            st,
            TraversalStats {
                nodes_visited: 1,
                prims_tested: 100
            }
        );
        // A ray missing the scene visits nothing.
        let mut st = TraversalStats::default();
        let away = Ray::new(Vec3::splat(-10.0), -Vec3::ONE);
        let bvh = Bvh::build(&bounds, SplitMethod::SahBinned);
        bvh.closest_hit(&away, f32::INFINITY, &mut st, |_, _| None);
        assert_eq!(st, TraversalStats::default());
        // The BVH tests far fewer triangles than brute force on a hitting ray.
        let mut st = TraversalStats::default();
        let r = Ray::new(vec3(0.0, 0.0, -10.0), Vec3::Z);
        bvh.any_hit(&r, f32::INFINITY, &mut st, |_| false);
        assert!(st.nodes_visited >= 1 && st.prims_tested < 100, "{st:?}");
    }

    #[test]
    fn visitor_sees_depths_from_root() {
        struct Depths(Vec<(u32, u32)>);
        impl TraversalVisitor for Depths {
            fn visit_node(&mut self, node: u32, depth: u32) {
                self.0.push((node, depth));
            }
        }
        let tris = random_tris(500, 3);
        let bounds = tri_bounds(&tris);
        let bvh = Bvh::build(&bounds, SplitMethod::SahBinned);
        let ray = Ray::new(vec3(-8.0, 0.1, 0.2), Vec3::X);
        let mut v = Depths(Vec::new());
        bvh.closest_hit(&ray, f32::INFINITY, &mut v, |_, _| None);
        assert_eq!(v.0[0], (0, 0));
        // Node 1 (root's first child) is always at depth 1 if visited.
        assert!(v.0.iter().all(|&(n, d)| n != 1 || d == 1));
        assert!(v.0.iter().all(|&(_, d)| d < bvh.depth()));
        assert!(v.0.len() > 3);
    }
}
