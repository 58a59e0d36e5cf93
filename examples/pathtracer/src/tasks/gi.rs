//! GI: a Cornell box seen through an inset that shows neither the light nor the left wall;
//! both are known only through the light they bounce onto what is visible.

use std::f32::consts::FRAC_PI_2;

use glam::{Vec3, Vec3A};

use super::{param, Aim, Scenario, Shot};
use crate::render::{Camera, Geometry, Lights, Material, OrientedBox, Quad, Scene};

/// The GI task.
pub struct Gi;

/// The inset camera (design and measurements: docs/tasks.md, GI). It stands at x = -0.9 and
/// turns right by half its field of view (LOOK is 4.2 deep and 4.2 tan(14 deg) = 1.046 to the
/// right), so the image's left edge is the plane x = -0.9: the left wall (x = -1) is never in
/// view, while the floor beside it, the back wall's left part and the tall box's left face,
/// the surfaces the wall lights most, are. The frustum's top stays below the ceiling.
pub(super) const CAMERA: Shot = Shot::new(EYE, Aim::At(LOOK), Vec3::Y, 28.0, (128, 128));
const EYE: Vec3 = Vec3::new(-0.9, 0.9, 3.2);
const LOOK: Vec3 = Vec3::new(0.146, 0.6, -1.0);

impl Scenario for Gi {
    fn scene(&self, theta: &[f64], camera: Camera) -> Scene {
        let p = |i| param(theta, i);
        let wall = |i| p(i).clamp(0.0, 1.0);
        // Box [-1, 1] x [0, 2] x [-1, 1], open at +z.
        let mut quads = vec![
            Quad::centered(Vec3::ZERO, Vec3::Z * 2.0, Vec3::X * 2.0, 0),
            Quad::centered(Vec3::new(0.0, 2.0, 0.0), Vec3::X * 2.0, Vec3::Z * 2.0, 0),
            Quad::centered(Vec3::new(0.0, 1.0, -1.0), Vec3::X * 2.0, Vec3::Y * 2.0, 0),
            Quad::centered(Vec3::new(-1.0, 1.0, 0.0), Vec3::Y * 2.0, Vec3::Z * 2.0, 1),
            Quad::centered(Vec3::new(1.0, 1.0, 0.0), Vec3::Z * 2.0, Vec3::Y * 2.0, 2),
        ];
        let mut lights = Lights::default();
        // Ceiling light, facing down (x x z = -y); theta_0, theta_1 span [-0.6, 0.6].
        lights.add_area(
            &mut quads,
            Quad::centered(
                Vec3::new(-0.6 + 1.2 * p(0), 1.995, -0.6 + 1.2 * p(1)),
                Vec3::X * 0.7,
                Vec3::Z * 0.7,
                3,
            ),
            Vec3::splat(9.0),
        );
        Scene {
            camera,
            geometry: Geometry {
                quads,
                boxes: vec![
                    // Tall box: theta_5 in [0, 1] is a quarter turn (the box's symmetry period).
                    OrientedBox::new(
                        Vec3::new(-0.35, 0.6, -0.35),
                        Vec3::new(0.3, 0.6, 0.3),
                        Vec3::Y,
                        FRAC_PI_2 * p(5),
                        0,
                    ),
                    OrientedBox::new(
                        Vec3::new(0.4, 0.3, 0.35),
                        Vec3::splat(0.3),
                        Vec3::Y,
                        -0.3,
                        0,
                    ),
                ],
                ..Default::default()
            },
            materials: vec![
                Material::grey(0.75),
                Material::Diffuse {
                    albedo: Vec3A::new(wall(2), wall(3), wall(4)),
                    texture: None,
                },
                Material::diffuse(0.15, 0.6, 0.15),
                Material::grey(0.0),
            ],
            textures: vec![],
            lights,
        }
    }

    /// [light x, light z, left wall r, g, b, tall-box rotation].
    fn start(&self) -> Vec<f64> {
        vec![0.2, 0.8, 0.2, 0.5, 0.8, 0.7]
    }

    fn target(&self) -> Vec<f64> {
        vec![0.5, 0.5, 0.8, 0.1, 0.1, 0.3]
    }

    /// The tall box's rotation: a quarter turn of a square box is the same box.
    fn periodic(&self) -> &'static [usize] {
        &[5]
    }
}
