//! Case 10: 1x1 and very non-square textures, texture coordinates of +-1e6 in every
//! wrap mode, NaN texture coordinates in the input.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use super::scenes::{load_error, mismatches};
use super::{Budget, Rendered, Row, render};
use glint::render::Renderer;
use glint::scene::components::{MeshData, Vertex};
use glint::scene::{
    Camera, Material, MaterialRef, Mesh, PointLight, Settings, TextureSource, Transform,
};
use glint::shade::texture::{Texture, WrapMode};

/// A camera looking at a textured unit quad `[-1, 1]^2` at z = 0 with per-corner
/// texture coordinates, shading off, so a pixel is its texel.
fn texture_render(
    b: &Budget,
    tex: &Arc<Texture>,
    wrap: [WrapMode; 2],
    uv: [Vec2; 4],
    bilinear: bool,
) -> glint::Result<Rendered> {
    let mut world = World::new();
    world.spawn(Camera {
        position: Vec3::new(0.0, 0.0, 2.0),
        look_at: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_degrees: 40.0,
        width: b.width,
        height: b.height(),
    });
    let material = world
        .spawn(Material {
            name: "textured".into(),
            kd_texture: Some(TextureSource::Decoded(tex.clone())),
            wrap,
            ..Default::default()
        })
        .id();
    let corner = |p: Vec3, t: Vec2| Vertex {
        position: p,
        normal: Vec3::Z,
        texcoord: t,
    };
    let data = MeshData {
        vertices: vec![
            corner(Vec3::new(-1.0, -1.0, 0.0), uv[0]),
            corner(Vec3::new(1.0, -1.0, 0.0), uv[1]),
            corner(Vec3::new(1.0, 1.0, 0.0), uv[2]),
            corner(Vec3::new(-1.0, 1.0, 0.0), uv[3]),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    world.spawn((
        Mesh {
            data: Arc::new(data),
        },
        Transform::default(),
        MaterialRef(material),
    ));
    world.spawn(PointLight {
        position: Vec3::new(0.0, 0.0, 3.0),
        color: Vec3::ONE,
    });
    world.insert_resource(Settings {
        shading: false,
        bilinear_filtering: bilinear,
        ..Default::default()
    });
    render(Renderer::from_world(world))
}

/// Case 10: 1x1 and very non-square textures, texture coordinates of +-1e6 in every wrap
/// mode, NaN texture coordinates in the input.
pub fn textures(b: &Budget) -> Vec<Row> {
    let mut rows = Vec::new();
    let modes = [WrapMode::Clamp, WrapMode::Repeat, WrapMode::MirroredRepeat];
    let far = [
        Vec2::new(-1e6, -1e6),
        Vec2::new(1e6, -1e6),
        Vec2::new(1e6, 1e6),
        Vec2::new(-1e6, 1e6),
    ];
    // 1x1: every lookup anywhere is the one texel.
    let one = Arc::new(Texture {
        width: 1,
        height: 1,
        texels: vec![Vec3::new(0.2, 0.4, 0.6)],
    });
    let mut wrong = 0.0;
    let mut nonfinite = 0.0;
    for mode in modes {
        for bilinear in [false, true] {
            match texture_render(b, &one, [mode; 2], far, bilinear) {
                Ok(img) => {
                    nonfinite += img.nonfinite();
                    wrong += mismatches(&img, Vec3::new(0.2, 0.4, 0.6), 1e-6);
                }
                Err(e) => rows.push(Row::error("texture 1x1", e)),
            }
        }
    }
    rows.push(Row::finite("texture 1x1, uv +-1e6", nonfinite));
    rows.push(Row::at_most(
        "texture 1x1, uv +-1e6",
        "pixels not the texel",
        wrong,
        0.0,
    ));

    // A 2x2 checker at constant uv = (+-1e6 + 1/4, -+1e6 + 3/4): f32 keeps 1/16 at 1e6,
    // and interpolation may move it by a few of those, still inside the same texel.
    let texels = vec![
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 1.0, 0.0),
    ];
    let checker = Arc::new(Texture {
        width: 2,
        height: 2,
        texels: texels.clone(),
    });
    let mut wrong = 0.0;
    let mut nonfinite = 0.0;
    for mode in [WrapMode::Repeat, WrapMode::MirroredRepeat] {
        for uv in [
            Vec2::new(1e6 + 0.25, -1e6 + 0.75),
            Vec2::new(-1e6 + 0.25, 1e6 + 0.75),
        ] {
            // Both u and v sit a quarter of a period into an even period: column 0 and
            // (v = 3/4, counted from the bottom) row 0.
            match texture_render(b, &checker, [mode; 2], [uv; 4], false) {
                Ok(img) => {
                    nonfinite += img.nonfinite();
                    wrong += mismatches(&img, texels[0], 1e-6);
                }
                Err(e) => rows.push(Row::error("texture 2x2", e)),
            }
        }
    }
    rows.push(Row::finite(
        "texture 2x2, uv +-1e6 repeat/mirror",
        nonfinite,
    ));
    rows.push(Row::at_most(
        "texture 2x2, uv +-1e6 repeat/mirror",
        "pixels not the expected texel",
        wrong,
        0.0,
    ));

    // 4096x1 and 1x4096 ramps: clamped +-1e6 reads the end texels; every mode stays finite
    // and inside the ramp's range.
    let ramp: Vec<Vec3> = (0..4096)
        .map(|i| Vec3::splat((i as f32 + 0.5) / 4096.0))
        .collect();
    let mut out_of_range = 0.0;
    let mut nonfinite = 0.0;
    let mut wrong_clamp = 0.0;
    for (w, h) in [(4096u32, 1u32), (1, 4096)] {
        let tex = Arc::new(Texture {
            width: w,
            height: h,
            texels: ramp.clone(),
        });
        for mode in modes {
            for bilinear in [false, true] {
                match texture_render(b, &tex, [mode; 2], far, bilinear) {
                    Ok(img) => {
                        nonfinite += img.nonfinite();
                        out_of_range += img
                            .image
                            .iter()
                            .filter(|p| {
                                !(p.min_element() >= ramp[0].x && p.max_element() <= ramp[4095].x)
                            })
                            .count() as f64;
                    }
                    Err(e) => rows.push(Row::error("texture ramp", e)),
                }
            }
            // Clamp at u = v = 1e6: the last texel along the ramp (x: right end, y: top = row 0).
            let end = if w > 1 { ramp[4095] } else { ramp[0] };
            if mode == WrapMode::Clamp {
                match texture_render(b, &tex, [mode; 2], [Vec2::splat(1e6); 4], true) {
                    Ok(img) => wrong_clamp += mismatches(&img, end, 1e-6),
                    Err(e) => rows.push(Row::error("texture ramp", e)),
                }
            }
        }
    }
    rows.push(Row::finite(
        "texture 4096x1 and 1x4096, uv +-1e6",
        nonfinite,
    ));
    rows.push(Row::at_most(
        "texture 4096x1 and 1x4096, uv +-1e6",
        "pixels outside the texel range",
        out_of_range,
        0.0,
    ));
    rows.push(Row::at_most(
        "texture 4096x1 and 1x4096, clamp at 1e6",
        "pixels not the end texel",
        wrong_clamp,
        0.0,
    ));

    let text = "(camera: (position: (0.0, 0.0, 3.0), look_at: (0.0, 0.0, 0.0)), materials: { \"m\": () }, entities: [Mesh((geometry: Inline(vertices: [(position: (0.0, 0.0, 0.0)), (position: (1.0, 0.0, 0.0), texcoord: (NaN, 0.5)), (position: (0.0, 1.0, 0.0))], triangles: [(0, 1, 2)]), material: Some(\"m\")))])";
    let rejected = load_error(text).is_some_and(|e| e.contains("vertices[1].texcoord"));
    rows.push(Row::exactly(
        "texture NaN texcoord in the input",
        "rejected at load, naming the field",
        rejected as u8 as f64,
        1.0,
    ));
    rows
}
