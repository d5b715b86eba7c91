//! Model import of the classic OBJ files in ../shared/assets (skipped with a printed
//! reason when absent).

mod common;

use glint::scene::Material;

use common::assets::{import, shared_assets};

#[test]
fn classic_obj_models_load_with_the_readme_triangle_counts() {
    let Some(assets) = shared_assets("classic_obj_models_load_with_the_readme_triangle_counts")
    else {
        return;
    };
    let c = assets.join("classic");
    let mcguire = c.join("cornell-box/mcguire");
    let mut cases = vec![
        (c.join("utah-teapot/teapot.obj"), 6_320),
        (c.join("utah-teapot/mcguire/teapot.obj"), 15_704),
        (c.join("stanford-bunny/stanford-bunny.obj"), 69_451),
        (c.join("stanford-dragon/dragon.obj"), 19_332),
        (c.join("suzanne/suzanne.obj"), 968),
        (c.join("cornell-box/original-measured/cornell_box.obj"), 36),
        (mcguire.join("CornellBox-Original.obj"), 36),
        (mcguire.join("CornellBox-Mirror.obj"), 36),
        (mcguire.join("CornellBox-Sphere.obj"), 2_188),
        (mcguire.join("CornellBox-Glossy.obj"), 1_112),
        (mcguire.join("CornellBox-Water.obj"), 7_088),
        (c.join("sponza-dabrovic/sponza.obj"), 66_450),
    ];
    for f in std::fs::read_dir(&mcguire).unwrap() {
        let f = f.unwrap().path();
        if f.file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with("CornellBox-Empty")
            && f.extension().is_some_and(|e| e == "obj")
        {
            cases.push((f, 12));
        }
    }
    for (f, n) in cases {
        let (mut world, report, warnings) =
            import(&f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(report.triangles, n, "{}", f.display());
        let (lo, hi) = report.bounds.unwrap();
        assert!(lo.is_finite() && hi.is_finite());
        let name = f.file_name().unwrap().to_string_lossy();
        if name == "dragon.obj" {
            // Its MTL file is missing upstream: one warning, default material.
            assert!(warnings.iter().any(|w| w.contains("material library")));
        } else {
            // McGuire's boxes have an emissive `light` material: noted, nothing else.
            assert!(
                warnings.iter().all(|w| w.contains("emissive")),
                "{}: {warnings:?}",
                f.display()
            );
        }
        if name == "sponza.obj" {
            // Every map_Kd resolves, some only case-insensitively.
            let mut q = world.query::<&Material>();
            let textured = q.iter(&world).filter(|m| m.kd_texture.is_some()).count();
            assert!(textured > 10, "{textured} textured materials");
        }
    }
}
