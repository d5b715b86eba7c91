//! Scene analysis: decides once which optional stages this scene and these settings need.

use bevy_ecs::prelude::*;

use crate::scene::{
    Acceleration, Material, Mesh, ParallelogramLight, PointLight, SegmentLight, Settings, Sphere,
};

/// One optional stage and whether it runs, with the reason.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlanEntry {
    /// The stage (system name).
    pub stage: &'static str,
    /// Whether it runs.
    pub runs: bool,
    /// Why (or why not).
    pub why: String,
}

/// Which optional stages run. Decided by [`analyse_scene`]; read by run conditions.
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub struct RenderPlan {
    /// Build a BVH over triangles (the scene has meshes).
    pub triangle_bvh: bool,
    /// Keep the binary triangle BVH after collapsing it to the 8-wide one (a
    /// [`BinaryBvhObserver`] walks it); a render traverses only the wide one.
    pub binary_triangle_bvh: bool,
    /// Build a BVH over spheres (the scene has spheres).
    pub sphere_bvh: bool,
    /// Decode textures and look them up (a material has one and texture mapping is on).
    pub textures: bool,
    /// Trace shadow rays (shadows on and at least one light).
    pub shadow_rays: bool,
    /// Shadow rays walk through transparent surfaces (transparency on and a material has alpha < 1).
    pub transparent_shadows: bool,
    /// Sample segment and parallelogram lights (the scene has one).
    pub area_lights: bool,
    /// Spawn reflection rays (reflections on, depth > 0, some ks non-zero).
    pub reflections: bool,
    /// Spawn pass-through rays (transparency on, depth > 0, some alpha < 1).
    pub pass_through: bool,
    /// Generate pixel sample patterns (more than one sample per pixel).
    pub pixel_patterns: bool,
    /// Every optional stage with its decision, in pipeline order, for `glint info`.
    pub entries: Vec<PlanEntry>,
}

impl RenderPlan {
    fn decide(&mut self, stage: &'static str, runs: bool, yes: &str, no: &str) -> bool {
        self.entries.push(PlanEntry {
            stage,
            runs,
            why: if runs { yes } else { no }.to_owned(),
        });
        runs
    }
}

/// Inserted before the prepare stage by a driver whose observers walk the binary
/// triangle BVH (the debug's traversal log and BVH view, `glint info`'s tree
/// statistics): names that observer. Without it the binary tree is dropped once
/// collapsed, since the render's queries traverse only the wide tree.
#[derive(Resource, Clone, Debug, PartialEq, Eq)]
pub struct BinaryBvhObserver(pub &'static str);

/// Query filter: any light entity.
type AnyLight = Or<(
    With<PointLight>,
    With<SegmentLight>,
    With<ParallelogramLight>,
)>;
/// Query filter: segment and parallelogram lights.
type AreaLight = Or<(With<SegmentLight>, With<ParallelogramLight>)>;

/// Analyses the scene and settings and writes the [`RenderPlan`].
#[allow(clippy::too_many_arguments)] // Because each is a part of the scene the plan reads.
pub fn analyse_scene(
    mut plan: ResMut<RenderPlan>,
    settings: Res<Settings>,
    meshes: Query<&Mesh>,
    spheres: Query<&Sphere>,
    materials: Query<&Material>,
    lights: Query<(), AnyLight>,
    area_lights: Query<(), AreaLight>,
    observer: Option<Res<BinaryBvhObserver>>,
) {
    let s = &*settings;
    let triangles: usize = meshes.iter().map(|m| m.data.triangles.len()).sum();
    let shared: Vec<u32> = super::geometry::mesh_uses(meshes.iter())
        .into_values()
        .filter(|&n| n >= 2)
        .collect();
    let lights = lights.iter().len();
    let area_lights = area_lights.iter().len();
    let textured = materials.iter().filter(|m| m.kd_texture.is_some()).count();
    let transparent = materials.iter().filter(|m| m.alpha < 1.0).count();
    let specular = materials
        .iter()
        .filter(|m| m.ks != glam::Vec3::ZERO)
        .count();
    let bvh = match s.acceleration {
        Acceleration::Bvh => "a BVH",
        Acceleration::None => "a single leaf (acceleration: none)",
    };

    let mut p = RenderPlan::default();
    p.triangle_bvh = p.decide(
        "build_triangle_bvh",
        triangles > 0,
        &if shared.is_empty() {
            format!("{triangles} triangles go into {bvh}")
        } else {
            format!(
                "{triangles} triangles go into {bvh}; {} meshes used {} times are instanced (two-level BVH)",
                shared.len(),
                shared.iter().sum::<u32>()
            )
        },
        "no meshes in the scene",
    );
    p.binary_triangle_bvh = p.decide(
        "keep binary triangle BVH",
        p.triangle_bvh && observer.is_some(),
        &format!("kept for {}", observer.as_ref().map_or("", |o| o.0)),
        if p.triangle_bvh {
            "no observer: dropped once collapsed, a render traverses the 8-wide BVH"
        } else {
            "no meshes in the scene"
        },
    );
    p.sphere_bvh = p.decide(
        "build_sphere_bvh",
        spheres.iter().len() > 0,
        &format!("{} spheres go into {bvh}", spheres.iter().len()),
        "no spheres in the scene",
    );
    p.textures = p.decide(
        "decode_textures",
        s.texture_mapping && textured > 0,
        &format!("{textured} textured materials"),
        if s.texture_mapping {
            "no material has a texture"
        } else {
            "texture_mapping is off"
        },
    );
    p.pixel_patterns = p.decide(
        "pixel sample patterns",
        s.pixel_samples > 1,
        &format!("{} samples per pixel", s.pixel_samples),
        "one sample per pixel, through its centre",
    );
    p.area_lights = p.decide(
        "area light sampling",
        area_lights > 0,
        &format!(
            "{area_lights} area lights, {} samples each",
            s.shadow_samples
        ),
        "no segment or parallelogram lights",
    );
    p.shadow_rays = p.decide(
        "trace_shadow_rays",
        s.shadows && lights > 0,
        "shadows on",
        if s.shadows {
            "no lights"
        } else {
            "shadows are off"
        },
    );
    p.transparent_shadows = p.decide(
        "transparent shadows",
        p.shadow_rays && s.transparency && transparent > 0,
        &format!("{transparent} materials with alpha < 1 tint the light"),
        "binary shadows: no shadow rays, transparency off, or every material opaque",
    );
    p.reflections = p.decide(
        "spawn_reflection_rays",
        s.reflections && s.max_depth > 0 && specular > 0,
        &format!("{specular} materials with ks > 0"),
        if !s.reflections {
            "reflections are off"
        } else if s.max_depth == 0 {
            "max_depth is 0"
        } else {
            "every material has ks = 0"
        },
    );
    p.pass_through = p.decide(
        "spawn_pass_through_rays",
        s.transparency && s.max_depth > 0 && transparent > 0,
        &format!("{transparent} materials with alpha < 1"),
        if !s.transparency {
            "transparency is off"
        } else if s.max_depth == 0 {
            "max_depth is 0"
        } else {
            "every material is opaque"
        },
    );
    *plan = p;
}
