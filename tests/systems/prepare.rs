//! Prepare: scene analysis, tables, acceleration structures.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use glint::scene::{
    Material, MaterialRef, Mesh, MeshData, PointLight, SegmentLight, Settings, Sphere,
    TextureSource, Transform, Vertex,
};
use glint::schedule::{RenderStats, Stage, StageErrors};
use glint::shade::texture::Texture;
use glint::trace::geometry::{SceneGeometry, build_sphere_bvh, build_triangle_bvh};
use glint::trace::lights::{Lights, gather_lights};
use glint::trace::materials::{Materials, decode_textures, gather_materials};
use glint::trace::plan::{RenderPlan, analyse_scene};

use crate::world::{material, run};

fn point_light() -> PointLight {
    PointLight {
        position: Vec3::new(0.0, 5.0, 0.0),
        color: Vec3::ONE,
    }
}

/// One triangle in the z = 0 plane with its corner at the origin.
fn triangle() -> Mesh {
    let vertex = |x: f32, y: f32| Vertex {
        position: Vec3::new(x, y, 0.0),
        normal: Vec3::Z,
        texcoord: Vec2::new(x, y),
    };
    Mesh {
        data: Arc::new(MeshData {
            vertices: vec![vertex(0.0, 0.0), vertex(1.0, 0.0), vertex(0.0, 1.0)],
            triangles: vec![[0, 1, 2]],
        }),
    }
}

#[test]
fn analyse_scene_plans_no_triangle_bvh_for_spheres_only() {
    let mut world = world![Settings::default(), RenderPlan::default()];
    let m = world.spawn(Material::default()).id();
    world.spawn((
        Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        },
        MaterialRef(m),
    ));
    world.spawn(point_light());
    run(&mut world, analyse_scene);
    let plan = world.resource::<RenderPlan>();
    assert!(!plan.triangle_bvh);
    assert!(plan.sphere_bvh);
    assert!(plan.shadow_rays, "shadows on and one light");
    assert!(!plan.textures && !plan.reflections && !plan.pass_through);
    assert!(!plan.area_lights && !plan.transparent_shadows && !plan.pixel_patterns);
    let entry = plan
        .entries
        .iter()
        .find(|e| e.stage == "build_triangle_bvh");
    assert_eq!(
        entry.map(|e| (e.runs, e.why.as_str())),
        Some((false, "no meshes in the scene"))
    );
}

#[test]
fn analyse_scene_plans_the_stages_a_scene_needs() {
    let settings = Settings {
        pixel_samples: 4,
        ..Settings::default()
    };
    let mut world = world![settings, RenderPlan::default()];
    let glass = world
        .spawn(Material {
            ks: Vec3::splat(0.5),
            alpha: 0.5,
            ..Material::default()
        })
        .id();
    world.spawn((triangle(), MaterialRef(glass)));
    world.spawn(SegmentLight {
        endpoint0: Vec3::ZERO,
        endpoint1: Vec3::X,
        color0: Vec3::ONE,
        color1: Vec3::ONE,
    });
    run(&mut world, analyse_scene);
    let plan = world.resource::<RenderPlan>();
    assert!(plan.triangle_bvh && !plan.sphere_bvh);
    assert!(plan.area_lights && plan.shadow_rays && plan.transparent_shadows);
    assert!(plan.reflections && plan.pass_through && plan.pixel_patterns);
    assert!(!plan.textures);
}

#[test]
fn gather_materials_indexes_every_material_entity() {
    let mut world = world![
        Settings::default(),
        Materials::default(),
        RenderStats::default()
    ];
    let plain = world
        .spawn(Material {
            kd: Vec3::new(0.1, 0.2, 0.3),
            ks: Vec3::splat(0.5),
            shininess: 8.0,
            alpha: 0.25,
            ..Material::default()
        })
        .id();
    let textured = world
        .spawn(Material {
            kd_texture: Some(TextureSource::File(PathBuf::from("wood.png"))),
            ..Material::default()
        })
        .id();
    run(&mut world, gather_materials);
    let table = world.resource::<Materials>();
    assert_eq!(table.list.len(), 2);
    let p = &table.list[table.index_of[&plain] as usize];
    assert_eq!(
        *p,
        material(Vec3::new(0.1, 0.2, 0.3), Vec3::splat(0.5), 8.0, 0.25)
    );
    let t = &table.list[table.index_of[&textured] as usize];
    assert_eq!(t.texture, Some(0));
    assert_eq!(table.sources.len(), 1, "one texture to decode");
    assert!(table.textures.is_empty(), "decoding is another stage");
    assert_eq!(
        world
            .resource::<RenderStats>()
            .items(Stage::GatherMaterials),
        2
    );
}

#[test]
fn gather_materials_drops_textures_when_texture_mapping_is_off() {
    let settings = Settings {
        texture_mapping: false,
        ..Settings::default()
    };
    let mut world = world![settings, Materials::default(), RenderStats::default()];
    world.spawn(Material {
        kd_texture: Some(TextureSource::File(PathBuf::from("wood.png"))),
        ..Material::default()
    });
    run(&mut world, gather_materials);
    let table = world.resource::<Materials>();
    assert_eq!(table.list[0].texture, None);
    assert!(table.sources.is_empty());
}

#[test]
fn gather_lights_tables_every_light_by_kind() {
    let mut world = world![Lights::default(), RenderStats::default()];
    world.spawn(point_light());
    world.spawn(PointLight {
        position: Vec3::X,
        color: Vec3::splat(2.0),
    });
    let segment = SegmentLight {
        endpoint0: Vec3::ZERO,
        endpoint1: Vec3::Y,
        color0: Vec3::ONE,
        color1: Vec3::ZERO,
    };
    world.spawn(segment);
    run(&mut world, gather_lights);
    let lights = world.resource::<Lights>();
    assert_eq!(lights.points.len(), 2);
    assert!(lights.points.contains(&point_light()));
    assert_eq!(lights.segments, vec![segment]);
    assert!(lights.parallelograms.is_empty());
    assert_eq!(
        world.resource::<RenderStats>().items(Stage::GatherLights),
        3
    );
}

#[test]
fn decode_textures_decodes_each_source_and_reports_unreadable_files() {
    let decoded = Arc::new(Texture {
        width: 2,
        height: 1,
        texels: vec![Vec3::X, Vec3::Y],
    });
    let materials = Materials {
        sources: vec![
            TextureSource::Decoded(decoded.clone()),
            TextureSource::File(PathBuf::from("/nonexistent/glint/texture.png")),
        ],
        ..Materials::default()
    };
    let mut world = world![materials, StageErrors::default(), RenderStats::default()];
    run(&mut world, decode_textures);
    let table = world.resource::<Materials>();
    assert_eq!(
        table.textures.len(),
        2,
        "one texture per source, even a failed one"
    );
    assert!(
        Arc::ptr_eq(&table.textures[0], &decoded),
        "decoded once, shared"
    );
    assert_eq!(
        table.textures[1].texels,
        vec![Vec3::ZERO],
        "a black stand-in"
    );
    let errors = &world.resource::<StageErrors>().0;
    assert_eq!(errors.len(), 1);
    assert!(
        errors[0].to_string().contains("texture.png"),
        "{}",
        errors[0]
    );
    assert_eq!(
        world.resource::<RenderStats>().items(Stage::DecodeTextures),
        3
    );
}

#[test]
fn build_triangle_bvh_puts_world_space_triangles_in_a_bvh() {
    let mut world = world![
        Settings::default(),
        RenderPlan::default(),
        Materials::default(),
        SceneGeometry::default(),
        RenderStats::default()
    ];
    let m = world.spawn(Material::default()).id();
    world.resource_mut::<Materials>().index_of.insert(m, 3);
    world.spawn((
        triangle(),
        Transform {
            world_from_object: Affine3A::from_translation(Vec3::new(0.0, 0.0, -2.0)),
        },
        MaterialRef(m),
    ));
    run(&mut world, build_triangle_bvh);
    let g = world.resource::<SceneGeometry>();
    assert_eq!(
        g.all_positions(),
        vec![[
            Vec3::new(0.0, 0.0, -2.0),
            Vec3::new(1.0, 0.0, -2.0),
            Vec3::new(0.0, 1.0, -2.0)
        ]]
    );
    assert_eq!(g.tri_normals, vec![[Vec3::Z; 3]]);
    assert_eq!(g.tri_texcoords[0][1], Vec2::X);
    assert_eq!(g.tri_material, vec![3]);
    let bounds = g.tri_wide.bounds;
    assert_eq!(
        (bounds.min, bounds.max),
        (Vec3::new(0.0, 0.0, -2.0), Vec3::new(1.0, 1.0, -2.0))
    );
    assert_eq!(g.tri_wide.triangles, 1);
    assert_eq!(g.tri_wide.prim_at(0, 0), 0);
    // No observer in the plan: the binary tree is dropped once collapsed.
    assert!(g.tri_bvh.nodes.is_empty() && g.tri_bvh.prim_indices.is_empty());
    assert!(g.sphere_bvh.nodes.is_empty());
    assert_eq!(
        world
            .resource::<RenderStats>()
            .items(Stage::BuildTriangleBvh),
        1
    );
}

#[test]
fn build_sphere_bvh_puts_every_sphere_in_a_bvh() {
    let mut world = world![
        Settings::default(),
        Materials::default(),
        SceneGeometry::default(),
        RenderStats::default()
    ];
    let m = world.spawn(Material::default()).id();
    world.resource_mut::<Materials>().index_of.insert(m, 1);
    for x in [-2.0, 2.0] {
        world.spawn((
            Sphere {
                center: Vec3::new(x, 0.0, 0.0),
                radius: 0.5,
            },
            MaterialRef(m),
        ));
    }
    run(&mut world, build_sphere_bvh);
    let g = world.resource::<SceneGeometry>();
    assert_eq!(g.spheres.len(), 2);
    assert_eq!(g.sphere_material, vec![1, 1]);
    let bounds = g.sphere_bvh.bounds();
    assert_eq!(
        (bounds.min, bounds.max),
        (Vec3::new(-2.5, -0.5, -0.5), Vec3::new(2.5, 0.5, 0.5))
    );
    assert!(g.tri_bvh.nodes.is_empty());
    assert_eq!(
        world.resource::<RenderStats>().items(Stage::BuildSphereBvh),
        2
    );
}
