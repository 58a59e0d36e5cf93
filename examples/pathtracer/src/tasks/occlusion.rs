//! OCCLUSION: bring a red sphere out from behind a blue one along the viewing axis.
//!
//! The camera, both sphere centres and their mirror images in the floor lie almost on one
//! line, so at the start the red sphere is hidden both directly and in the floor's
//! reflection: moving it further back or forward (until it pokes out of the blue sphere's
//! front) changes nothing, a plateau. At the target it sits in front of the blue sphere.

use glam::{Vec3, Vec3A};

use super::{param, Aim, Scenario, Shot};
use crate::render::{Camera, Geometry, Lights, Material, Quad, Scene, Sphere};

/// Far down the viewing axis, through the room's open front (why: docs/tasks.md, OCCLUSION).
pub(super) const CAMERA: Shot = Shot::new(EYE, Aim::Along(Vec3::NEG_Z), Vec3::Y, 16.0, (128, 96));
const EYE: Vec3 = Vec3::new(0.0, 0.5, 20.0);

/// The OCCLUSION task.
pub struct Occlusion;

/// Depth (world z) of the red sphere's centre: theta in [0, 1] spans z in [-4, 6]; the
/// camera is at z = 8, the blue sphere at z = 3.
fn red_z(theta: f32) -> f32 {
    -3.0 + 8.0 * theta.clamp(-0.25, 1.1)
}

impl Scenario for Occlusion {
    fn scene(&self, theta: &[f64], camera: Camera) -> Scene {
        let mut quads = vec![
            // Glass floor facing up (z x x = +y), dark base below it.
            Quad::centered(Vec3::new(0.0, 0.0, 1.0), Vec3::Z * 14.0, Vec3::X * 8.0, 0),
            Quad::centered(Vec3::new(0.0, -0.3, 1.0), Vec3::Z * 14.0, Vec3::X * 8.0, 1),
            // Back wall, side walls, ceiling.
            Quad::centered(Vec3::new(0.0, 2.0, -6.0), Vec3::X * 8.0, Vec3::Y * 4.6, 2),
            Quad::centered(Vec3::new(-4.0, 2.0, 1.0), Vec3::Y * 4.6, Vec3::Z * 14.0, 3),
            Quad::centered(Vec3::new(4.0, 2.0, 1.0), Vec3::Z * 14.0, Vec3::Y * 4.6, 3),
            Quad::centered(Vec3::new(0.0, 4.0, 1.0), Vec3::X * 8.0, Vec3::Z * 14.0, 2),
        ];
        let mut lights = Lights::default();
        // Facing down: x x z = -y.
        lights.add_area(
            &mut quads,
            Quad::centered(Vec3::new(0.0, 3.98, 1.0), Vec3::X * 6.0, Vec3::Z * 10.0, 6),
            Vec3::splat(1.6),
        );
        Scene {
            camera,
            geometry: Geometry {
                quads,
                spheres: vec![
                    Sphere::new(Vec3::new(0.0, 0.5, 3.0), 0.45, 4),
                    Sphere::new(Vec3::new(0.0, 0.5, red_z(param(theta, 0))), 0.25, 5),
                ],
                ..Default::default()
            },
            materials: vec![
                Material::Dielectric { ior: 1.5 },
                Material::grey(0.03),
                Material::grey(0.75),
                Material::diffuse(0.7, 0.68, 0.6),
                Material::diffuse(0.08, 0.12, 0.8),
                Material::diffuse(0.85, 0.06, 0.05),
                Material::grey(0.0),
            ],
            textures: vec![],
            lights: Lights {
                environment: Vec3A::ZERO,
                ..lights
            },
        }
    }

    fn start(&self) -> Vec<f64> {
        vec![0.6]
    }

    fn target(&self) -> Vec<f64> {
        vec![0.85]
    }
}
