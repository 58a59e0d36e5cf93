//! SHADOW: move a sphere that the camera cannot see so that its shadow lands right.
//!
//! The scene is the authors' (SPEC section 2), in world units.

use glam::{Vec3, Vec3A};

use super::{param, Aim, Scenario, Shot};
use crate::render::{Camera, Geometry, Lights, Material, PointLight, Quad, Scene, Sphere};

/// The authors' camera: along -x with +z up (image right = +y), 40 degrees.
pub(super) const CAMERA: Shot = Shot::new(EYE, Aim::Along(Vec3::NEG_X), Vec3::Z, HFOV, (256, 192));
const EYE: Vec3 = Vec3::new(17.658, 0.0, 0.0);
const HFOV: f64 = 39.597755;

/// The SHADOW task.
pub struct Shadow;

impl Scenario for Shadow {
    fn scene(&self, theta: &[f64], camera: Camera) -> Scene {
        let center = Vec3::new(13.57, 8.05 + param(theta, 0), -2.0 + param(theta, 1));
        Scene {
            camera,
            geometry: Geometry {
                // y x z = +x: the wall faces the camera.
                quads: vec![Quad::centered(
                    Vec3::ZERO,
                    Vec3::Y * 13.16,
                    Vec3::Z * 13.16,
                    0,
                )],
                spheres: vec![Sphere::new(center, 0.5, 1)],
                ..Default::default()
            },
            materials: vec![Material::grey(0.7), Material::diffuse(0.8, 0.262, 0.0415)],
            textures: vec![],
            lights: Lights {
                points: vec![PointLight::new(
                    Vec3::new(25.975, 13.776, 0.0),
                    Vec3::splat(1715.0),
                )],
                environment: Vec3A::new(0.6, 0.6, 0.99),
                environment_nee: false,
                ..Default::default()
            },
        }
    }

    fn start(&self) -> Vec<f64> {
        vec![-0.5, 2.5]
    }

    fn target(&self) -> Vec<f64> {
        vec![-1.5, 1.0]
    }
}
