//! `glint info`: what a scene holds and which stages a render of it runs, and why.

use std::fmt::Write;

use bevy_ecs::prelude::*;

use crate::accel::leaf::{LANES, TriGroup};
use crate::error::Result;
use crate::render::Renderer;
use crate::scene::{Material, Mesh, ParallelogramLight, PointLight, SegmentLight, Sphere};
use crate::trace::geometry::SceneGeometry;
use crate::trace::plan::BinaryBvhObserver;

/// A human-readable report of the scene and its render plan (runs the prepare stage,
/// keeping the binary triangle BVH for its statistics).
pub fn describe(renderer: &mut Renderer) -> Result<String> {
    renderer
        .world
        .insert_resource(BinaryBvhObserver("glint info's tree statistics"));
    renderer.prepare()?;
    let w = &mut renderer.world;
    let count = |w: &mut World, f: fn(&mut World) -> usize| f(w);
    let meshes = count(w, |w| w.query::<&Mesh>().iter(w).len());
    let spheres = count(w, |w| w.query::<&Sphere>().iter(w).len());
    let materials = count(w, |w| w.query::<&Material>().iter(w).len());
    let points = count(w, |w| w.query::<&PointLight>().iter(w).len());
    let segments = count(w, |w| w.query::<&SegmentLight>().iter(w).len());
    let parallelograms = count(w, |w| w.query::<&ParallelogramLight>().iter(w).len());
    let camera = renderer.camera();
    let geometry = renderer.world.resource::<SceneGeometry>();
    let bounds = geometry.bounds();
    let mut out = String::new();
    let o = &mut out;
    let _ = writeln!(o, "scene");
    if let Some(c) = camera {
        let _ = writeln!(
            o,
            "  camera        {}x{} at {} looking at {}, fov {} deg",
            c.width, c.height, c.position, c.look_at, c.fov_y_degrees
        );
    }
    let _ = writeln!(
        o,
        "  meshes        {meshes} ({} triangles)",
        geometry.triangles_drawn()
    );
    let instanced = &geometry.instanced;
    if !instanced.is_empty() {
        let _ = writeln!(
            o,
            "  instances     {} of {} shared meshes ({} triangles stored once each)",
            instanced.instances.len(),
            instanced.meshes.len(),
            geometry.triangles_stored() - geometry.triangles_flattened() as u64
        );
    }
    let _ = writeln!(o, "  spheres       {spheres}");
    let _ = writeln!(o, "  materials     {materials}");
    let _ = writeln!(
        o,
        "  lights        {points} point, {segments} segment, {parallelograms} parallelogram"
    );
    if bounds.is_empty() {
        let _ = writeln!(o, "  bounds        (no geometry)");
    } else {
        let _ = writeln!(o, "  bounds        {} .. {}", bounds.min, bounds.max);
    }
    let bvh = &geometry.tri_bvh;
    if !bvh.nodes.is_empty() {
        let _ = writeln!(
            o,
            "  triangle BVH  {} nodes, {} leaves, depth {}",
            bvh.nodes.len(),
            bvh.leaf_count(),
            bvh.depth()
        );
    }
    let stored = geometry.triangles_stored();
    if !bvh.nodes.is_empty() && stored > 0 {
        let bytes = size_of_val(bvh.nodes.as_slice())
            + size_of_val(bvh.prim_indices.as_slice())
            + size_of_val(geometry.tri_lanes.as_slice());
        let _ = writeln!(
            o,
            "  binary BVH    {bytes} bytes, {:.1} per stored triangle (kept for observers; a render drops it)",
            bytes as f64 / stored as f64
        );
    }
    if stored > 0 {
        let bytes = geometry.triangle_bytes();
        let _ = writeln!(
            o,
            "  accel memory  {bytes} bytes, {:.1} per stored triangle (nodes, leaf vertices, indices)",
            bytes as f64 / stored as f64
        );
    }
    let wide = &geometry.tri_wide;
    if wide.triangles > 0 {
        // Per flattened triangle: where the accel memory goes.
        let per = |bytes: usize| bytes as f64 / wide.triangles as f64;
        let padding = wide.leaves.groups.len() * LANES - wide.triangles;
        // A group's vertices, without its lanes' triangle indices (reported apart).
        let vertex_bytes = size_of::<TriGroup>() - size_of::<[u32; LANES]>();
        let _ = writeln!(
            o,
            "  wide BVH      per flattened triangle: nodes {:.1}, leaf vertices {:.1} ({:.1} of it NaN padding), indices {:.1} ({:.1} of it padding)",
            per(size_of_val(wide.nodes.as_slice())),
            per(wide.leaves.groups.len() * vertex_bytes),
            per(padding * vertex_bytes / LANES),
            per(wide.leaves.groups.len() * size_of::<[u32; LANES]>()),
            per(padding * size_of::<u32>()),
        );
    }
    let sampler = ron::to_string(&renderer.settings().sampler).unwrap_or_default();
    let _ = writeln!(
        o,
        "  samples       {} per pixel, {sampler} sampler",
        renderer.samples_per_pixel()
    );
    let _ = writeln!(o, "plan");
    for e in &renderer.plan().entries {
        let mark = if e.runs { "runs   " } else { "skipped" };
        let _ = writeln!(o, "  {mark} {:<26} {}", e.stage, e.why);
    }
    for warning in renderer.warnings() {
        let _ = writeln!(o, "warning: {warning}");
    }
    Ok(out)
}
