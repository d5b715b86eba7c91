//! Where the 8-wide BVH's memory goes, per mesh (torus 100k and 1M, Cornell, and the
//! bunny, Sponza and MetalRoughSpheres when ../shared/assets is present): bytes per
//! triangle (nodes, leaves), nodes and depth, triangle groups and their padding lanes,
//! node lanes by kind, and the leaf-size histograms (1 to 16+ triangles) of the binary
//! tree and of the wide one:
//!   cargo run --release -p glint-bench --example leaf_stats

use glint::accel::leaf::{LANES, leaf_count};
use glint::accel::{Bvh, SplitMethod, WideBvh};
use glint_bench::{assets_dir, cornell_scene, displaced_torus, find_file, load_model};

/// Prints the statistics of the wide BVH over `tris`.
fn stats(label: &str, tris: &[[glam::Vec3; 3]]) {
    let bounds = glint_bench::triangle_boxes(tris);
    let bvh = Bvh::build(&bounds, SplitMethod::SahBinned);
    let wide = WideBvh::collapse(&bvh, tris);
    let mut bin = [0usize; 17];
    for n in bvh.nodes.iter().filter(|n| n.is_leaf()) {
        bin[(n.count as usize).min(16)] += 1;
    }
    let mut lanes = [0usize; 17];
    let (mut leaf_lanes, mut inner_lanes, mut empty) = (0, 0, 0);
    for node in &wide.nodes {
        for l in 0..8 {
            if node.child[l] == u32::MAX {
                empty += 1;
            } else if node.count[l] == 0 {
                inner_lanes += 1;
            } else {
                leaf_lanes += 1;
                lanes[leaf_count(node.count[l]).0.min(16)] += 1;
            }
        }
    }
    let groups = wide.leaves.groups.len();
    let pad = groups * LANES - tris.len();
    let per = |b: usize| b as f64 / tris.len() as f64;
    glint_bench::outln!(
        "{label}: {} tris, {:.2} B/tri (nodes {:.2}, leaves {:.2}), {} nodes depth {}, groups {groups}, padding lanes {pad} ({:.1}%), lanes: leaf {leaf_lanes} inner {inner_lanes} empty {empty}",
        tris.len(),
        per(wide.bytes()),
        per(size_of_val(wide.nodes.as_slice())),
        per(wide.leaves.bytes()),
        wide.nodes.len(),
        wide.depth,
        100.0 * pad as f64 / (groups * LANES) as f64,
    );
    glint_bench::outln!("  binary leaf sizes: {:?}", &bin[1..]);
    glint_bench::outln!("  wide leaf sizes:   {:?}", &lanes[1..]);
}

fn main() {
    stats("torus100k", &displaced_torus(158));
    stats("torus1M", &displaced_torus(500));
    if let Ok(t) = load_model(&cornell_scene()) {
        stats("cornell", &t);
    }
    if let Some(a) = assets_dir() {
        for (label, dir, ext) in [
            ("bunny", "classic/stanford-bunny", "obj"),
            ("sponza", "classic/sponza-dabrovic", "obj"),
            (
                "mrspheres",
                "khronos-gltf/MetalRoughSpheresNoTextures/glTF-Binary",
                "glb",
            ),
        ] {
            match find_file(&a.join(dir), ext).and_then(|p| load_model(&p)) {
                Ok(t) => stats(label, &t),
                Err(e) => glint_bench::outln!("{label}: {e}"),
            }
        }
    }
}
