//! Tests of the scene geometry's queries where a triangle sits in two leaves.

use super::*;
use crate::accel::BvhNode;
use crate::shade::texture::WrapMode;
use crate::trace::materials::MaterialData;

#[test]
fn a_transparent_triangle_in_two_leaves_is_crossed_once() {
    let tri = [
        Vec3::ZERO,
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
    ];
    // The triangle in two leaves, as a spatial split leaves it, whose boxes overlap
    // around x = 1.
    let whole = Aabb::from_points(&tri);
    let (mut left, mut right) = (whole, whole);
    (left.max.x, right.min.x) = (1.2, 0.8);
    let tri_bvh = Bvh {
        nodes: vec![
            BvhNode::interior(whole, 2),
            BvhNode::leaf(left, 0, 1),
            BvhNode::leaf(right, 1, 1),
        ]
        .into(),
        prim_indices: vec![0, 0].into(),
    };
    let mut g = SceneGeometry {
        tri_normals: vec![[Vec3::Z; 3]],
        tri_texcoords: vec![[Vec2::ZERO; 3]],
        tri_material: vec![0],
        tri_bvh,
        ..Default::default()
    };
    g.collapse_triangle_bvh(&[tri]);
    g.tri_wide.validate(&[tri]).unwrap();
    let (alpha, kd) = (0.5, Vec3::new(0.2, 0.5, 0.8));
    let materials = Materials {
        list: vec![MaterialData {
            kd,
            ks: Vec3::ZERO,
            shininess: 1.0,
            alpha,
            texture: None,
            wrap: [WrapMode::Clamp; 2],
        }],
        ..Default::default()
    };
    let once = (1.0 - alpha) * (Vec3::ONE - (Vec3::ONE - kd) * alpha);
    let ray = Ray::new(Vec3::new(1.0, 0.5, 1.0), Vec3::new(0.0, 0.0, -2.0));
    // Both lanes meet the ray: the wide tree reports the triangle twice.
    let mut met = 0;
    g.tri_wide.any_hit(&ray, 1.0, |_, _| {
        met += 1;
        false
    });
    assert_eq!(met, 2);
    // The wide tree (unobserved queries) and the binary one (observed) alike.
    assert_eq!(g.transmittance(&ray, 1.0, &materials, &mut ()), once);
    let mut stats = TraversalStats::default();
    assert_eq!(g.transmittance(&ray, 1.0, &materials, &mut stats), once);
    assert_eq!(stats.prims_tested, 2);
    // And it is still one surface to the closest hit.
    let hit = g.intersect(&ray, f32::INFINITY, &mut ()).expect("a hit");
    assert_eq!((hit.prim, hit.t), (0, 0.5));
}
