//! Model import of the Khronos glTF sample files in ../shared/assets (skipped with a
//! printed reason when absent): every file loads with the README's triangle count and
//! renders; the test models land, face and wrap as labelled.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use glam::Vec3;
use glint::Renderer;
use glint::scene::{Material, MaterialRef, Mesh, Transform};
use glint::shade::texture::WrapMode;

use common::assets::{import, readme_counts, render_image, shared_assets, small};

fn gltf_files(assets: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for model in std::fs::read_dir(assets.join("khronos-gltf")).unwrap() {
        let model = model.unwrap().path();
        let Ok(variants) = std::fs::read_dir(&model) else {
            continue;
        };
        for variant in variants {
            let Ok(entries) = std::fs::read_dir(variant.unwrap().path()) else {
                continue;
            };
            for f in entries {
                let f = f.unwrap().path();
                if matches!(f.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
                    files.push(f);
                }
            }
        }
    }
    files.sort();
    files
}

#[test]
fn every_khronos_file_loads_counts_and_renders() {
    let Some(assets) = shared_assets("every_khronos_file_loads_counts_and_renders") else {
        return;
    };
    let counts = readme_counts(&assets);
    let files = gltf_files(&assets);
    assert!(files.len() >= 70, "found {} files", files.len());
    let mut failures = Vec::new();
    for f in &files {
        let folder = f
            .parent()
            .and_then(Path::parent)
            .and_then(Path::file_name)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let variant = f.parent().unwrap().file_name().unwrap().to_string_lossy();
        let expected_error = match variant.as_ref() {
            "glTF-Draco" => Some("KHR_draco_mesh_compression"),
            "glTF-Quantized" => Some("KHR_mesh_quantization"),
            _ => None,
        };
        let result = import(f);
        match (result, expected_error) {
            (Err(e), Some(ext)) => {
                let msg = e.to_string();
                if !msg.contains(ext) || msg.lines().count() != 1 {
                    failures.push(format!("{}: unclear error: {msg}", f.display()));
                }
            }
            (Ok(_), Some(ext)) => failures.push(format!(
                "{}: loaded, expected an error naming {ext}",
                f.display()
            )),
            (Err(e), None) => failures.push(format!("{}: {e}", f.display())),
            (Ok((_, report, _)), None) => {
                match counts.get(&folder) {
                    None => failures.push(format!("{folder}: no count in the assets README")),
                    Some(&n) if report.triangles != n => failures.push(format!(
                        "{}: {} triangles, README says {n}",
                        f.display(),
                        report.triangles
                    )),
                    Some(_) => {}
                }
                let (lo, hi) = report.bounds.expect("bounds");
                if !(lo.is_finite() && hi.is_finite()) {
                    failures.push(format!("{}: bounds not finite", f.display()));
                }
                // One render per model folder and variant is enough; the 1M-triangle file
                // renders once (its .gltf), at the same size.
                let big = folder == "MetalRoughSpheresNoTextures" && variant == "glTF-Binary";
                if !big {
                    let image = render_image(Renderer::from_model(f, &small()).unwrap());
                    if image.iter().any(|p| !p.is_finite()) {
                        failures.push(format!("{}: non-finite pixel", f.display()));
                    }
                    if image.iter().all(|p| *p == Vec3::ZERO) {
                        failures.push(format!("{}: all black", f.display()));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn khronos(assets: &Path, model: &str, variant: &str, file: &str) -> PathBuf {
    assets
        .join("khronos-gltf")
        .join(model)
        .join(variant)
        .join(file)
}

/// World-space vertices of the mesh entity whose name starts with `prefix`.
fn world_vertices(world: &mut World, prefix: &str) -> (Vec<Vec3>, Vec<glam::Vec2>, Entity) {
    let mut q = world.query::<(&Name, &Mesh, &Transform, &MaterialRef)>();
    let (_, mesh, t, m) = q
        .iter(world)
        .find(|(n, ..)| n.as_str().starts_with(prefix))
        .unwrap_or_else(|| panic!("no mesh named {prefix}*"));
    let p = mesh
        .data
        .vertices
        .iter()
        .map(|v| t.world_from_object.transform_point3(v.position))
        .collect();
    let uv = mesh.data.vertices.iter().map(|v| v.texcoord).collect();
    (p, uv, m.0)
}

fn mean<T: Copy + std::iter::Sum<T> + std::ops::Div<f32, Output = T>>(v: &[T]) -> T {
    v.iter().copied().sum::<T>() / v.len() as f32
}

#[test]
fn texture_coordinate_test_corners_land_where_labelled() {
    let Some(assets) = shared_assets("texture_coordinate_test_corners_land_where_labelled") else {
        return;
    };
    let f = khronos(
        &assets,
        "TextureCoordinateTest",
        "glTF",
        "TextureCoordinateTest.gltf",
    );
    let (mut world, report, _) = import(&f).unwrap();
    let (lo, hi) = report.bounds.unwrap();
    let centre = 0.5 * (lo + hi);
    // Each labelled square sits in its corner of the model (x right, y up, facing +z) and
    // reads the same corner of the image: glint's v runs up, so "top" is v > 0.5.
    for (name, right, top) in [
        ("TopLeftObj", false, true),
        ("TopRightObj", true, true),
        ("BottomLeftObj", false, false),
        ("BottomRightObj", true, false),
    ] {
        let (p, uv, _) = world_vertices(&mut world, name);
        let (p, uv) = (mean(&p), mean(&uv));
        assert_eq!(p.x > centre.x, right, "{name} at {p}");
        assert_eq!(p.y > centre.y, top, "{name} at {p}");
        assert_eq!(uv.x > 0.5, right, "{name} reads u = {}", uv.x);
        assert_eq!(uv.y > 0.5, top, "{name} reads v = {}", uv.y);
    }
}

#[test]
fn orientation_test_arrows_point_at_their_targets() {
    let Some(assets) = shared_assets("orientation_test_arrows_point_at_their_targets") else {
        return;
    };
    let f = khronos(&assets, "OrientationTest", "glTF", "OrientationTest.gltf");
    let (mut world, _, _) = import(&f).unwrap();
    for axis in ["X1", "X2", "Y1", "Y2", "Z1", "Z2"] {
        let (arrow, _, _) = world_vertices(&mut world, &format!("Arrow{axis}/"));
        let (target, _, _) = world_vertices(&mut world, &format!("Target{axis}/"));
        let mut q = world.query::<(&Name, &Transform)>();
        let base: Vec3 = q
            .iter(&world)
            .find(|(n, _)| n.as_str().starts_with(&format!("Arrow{axis}/")))
            .unwrap()
            .1
            .world_from_object
            .translation
            .into();
        // The tip is the arrow vertex farthest from the node's origin (the arrow's base).
        let tip = arrow
            .iter()
            .copied()
            .max_by(|a, b| a.distance(base).total_cmp(&b.distance(base)))
            .unwrap();
        // Compare directions in the plane the node rotates in (across its axis); the
        // arrow head's thickness along the axis is not part of the test.
        let rotation_axis = match &axis[..1] {
            "X" => Vec3::X,
            "Y" => Vec3::Y,
            _ => Vec3::Z,
        };
        let flat = |v: Vec3| v - v.dot(rotation_axis) * rotation_axis;
        let angle = flat(tip - base)
            .angle_between(flat(mean(&target) - base))
            .to_degrees();
        println!("Arrow{axis}: {angle:.2} degrees off its target");
        // A transposed rotation turns the arrows 10 to 70 degrees away.
        assert!(
            angle < 3.0,
            "Arrow{axis} points {angle} degrees off its target"
        );
    }
}

#[test]
fn negative_scale_test_keeps_normals_outward() {
    let Some(assets) = shared_assets("negative_scale_test_keeps_normals_outward") else {
        return;
    };
    let f = khronos(
        &assets,
        "NegativeScaleTest",
        "glTF-Binary",
        "NegativeScaleTest.glb",
    );
    let (mut world, _, _) = import(&f).unwrap();
    let mut mirrored = 0;
    let mut q = world.query::<(&Name, &Mesh, &Transform)>();
    for (name, mesh, t) in q.iter(&world) {
        let m = t.world_from_object;
        if m.matrix3.determinant() < 0.0 {
            mirrored += 1;
        }
        let normal_from_object = m.matrix3.inverse().transpose();
        let v = &mesh.data.vertices;
        let (mut agree, mut total) = (0, 0);
        for tri in &mesh.data.triangles {
            let [a, b, c] = tri.map(|i| &v[i as usize]);
            let [pa, pb, pc] = [a, b, c].map(|v| m.transform_point3(v.position));
            let ng = (pb - pa).cross(pc - pa);
            if ng.length() < 1e-12 {
                continue;
            }
            let n: Vec3 =
                (normal_from_object * glam::Vec3A::from(a.normal + b.normal + c.normal)).into();
            total += 1;
            if ng.dot(n) > 0.0 {
                agree += 1;
            }
        }
        // The winding (geometric normal) and the vertex normals agree after mirroring.
        assert!(
            agree as f64 >= 0.99 * total as f64,
            "{name}: {agree} of {total} triangles face along their normals"
        );
    }
    assert!(mirrored > 0, "the file has mirrored nodes");
}

#[test]
fn texture_settings_test_wrap_modes_follow_the_samplers() {
    let Some(assets) = shared_assets("texture_settings_test_wrap_modes_follow_the_samplers") else {
        return;
    };
    let f = khronos(
        &assets,
        "TextureSettingsTest",
        "glTF",
        "TextureSettingsTest.gltf",
    );
    let (mut world, _, _) = import(&f).unwrap();
    let mut q = world.query::<&Material>();
    let wrap: HashMap<String, [WrapMode; 2]> =
        q.iter(&world).map(|m| (m.name.clone(), m.wrap)).collect();
    use WrapMode::*;
    // Samplers as the file sets them (wrapS, wrapT), per the README's tests.
    assert_eq!(wrap["TextureRepeatMaterialT"], [Clamp, Repeat]);
    assert_eq!(wrap["TextureClampMaterialT"], [Repeat, Clamp]);
    assert_eq!(wrap["TextureMirrorMaterialT"], [Repeat, MirroredRepeat]);
    assert_eq!(wrap["TextureRepeatMaterialS"], [Repeat, Clamp]);
    assert_eq!(wrap["TextureClampMaterialS"], [Clamp, Repeat]);
    assert_eq!(wrap["TextureMirrorMaterialS"], [MirroredRepeat, Repeat]);
    // And they matter: the same texture read past its edge differs by mode.
    let mut q = world.query::<&Material>();
    let m = q
        .iter(&world)
        .find(|m| m.name == "TextureRepeatMaterialT")
        .unwrap();
    let Some(glint::scene::TextureSource::Decoded(t)) = &m.kd_texture else {
        panic!("decoded texture expected");
    };
    let differ = |a: WrapMode, b: WrapMode| {
        (0..64 * 64).any(|k| {
            let (i, j) = ((k % 64) as f32, (k / 64) as f32);
            let uv = glam::Vec2::new((i + 0.5) / 64.0, 1.0 + (j + 0.5) / 64.0);
            t.sample_nearest(uv, [Clamp, a]) != t.sample_nearest(uv, [Clamp, b])
        })
    };
    assert!(
        differ(Repeat, Clamp) && differ(Repeat, MirroredRepeat) && differ(Clamp, MirroredRepeat)
    );
}

#[test]
fn box_textured_renders_identically_in_all_three_forms() {
    let Some(assets) = shared_assets("box_textured_renders_identically_in_all_three_forms") else {
        return;
    };
    let images: Vec<Vec<Vec3>> = [
        ("glTF", "BoxTextured.gltf"),
        ("glTF-Binary", "BoxTextured.glb"),
        ("glTF-Embedded", "BoxTextured.gltf"),
    ]
    .iter()
    .map(|(v, f)| {
        render_image(
            Renderer::from_model(&khronos(&assets, "BoxTextured", v, f), &small()).unwrap(),
        )
    })
    .collect();
    assert!(images[0].iter().any(|p| p.max_element() > 0.1));
    assert_eq!(images[0], images[1]);
    assert_eq!(images[0], images[2]);
}
