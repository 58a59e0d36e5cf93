//! CAUSTIC: find a light outside the view from the caustic it casts through a glass ball.

use glam::{Vec3, Vec3A};

use super::{param, unit_box, Defaults, Paper, Task, View};
use crate::render::{Geometry, Lights, Material, Quad, Scene, Sphere};

/// The CAUSTIC task.
pub struct Caustic;

impl Caustic {
    /// The task (analytic shapes only).
    pub fn new() -> Self {
        Caustic
    }
}

/// Height of the emitter's plane; theta in [0, 1]^2 spans x, z in [-2, 2] on it.
const LIGHT_HEIGHT: f32 = 3.0;

impl Task for Caustic {
    fn name(&self) -> &'static str {
        "caustic"
    }

    fn description(&self) -> &'static str {
        "Move a small area light above the view (x, z, normalised) so that the caustic it casts through a glass sphere matches the reference."
    }

    fn dim(&self) -> usize {
        2
    }

    fn defaults(&self) -> Defaults {
        Defaults {
            samples: 4,
            sigma0: 0.125,
            spp: 32,
            lr: 0.01,
            iterations: 500,
        }
    }

    fn paper(&self) -> Option<Paper> {
        Some(Paper {
            image_mse: 1.89e-5,
            param_mse: 9.76e-5,
            seconds_per_iteration: 0.08,
            mitsuba_image_mse: 3.12e-1,
            mitsuba_param_mse: 8.50,
            sigma05: Some((2.4e-3, 2.2e-4)),
        })
    }

    fn start(&self) -> Vec<f64> {
        vec![0.75, 0.7]
    }

    fn target(&self) -> Vec<f64> {
        vec![0.3, 0.35]
    }

    fn bounds(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        unit_box(2)
    }

    fn max_depth(&self) -> u32 {
        8
    }

    fn scene(&self, theta: &[f64], view: View) -> Scene {
        let eye = Vec3::new(0.0, 3.5, 6.0);
        let camera = view.camera(
            eye,
            Vec3::new(0.0, 0.4, 0.0) - eye,
            Vec3::Y,
            45.0,
            (128, 96),
        );
        let light_at = Vec3::new(
            -2.0 + 4.0 * param(theta, 0),
            LIGHT_HEIGHT,
            -2.0 + 4.0 * param(theta, 1),
        );
        // Ground facing up (z x x = +y).
        let mut quads = vec![Quad::centered(
            Vec3::ZERO,
            Vec3::Z * 16.0,
            Vec3::X * 16.0,
            0,
        )];
        let mut lights = Lights {
            environment: Vec3A::splat(0.05),
            environment_nee: false,
            ..Default::default()
        };
        // Facing down (x x z = -y).
        lights.add_area(
            &mut quads,
            Quad::centered(light_at, Vec3::X * 1.0, Vec3::Z * 1.0, 1),
            Vec3::splat(25.0),
        );
        Scene {
            camera,
            geometry: Geometry {
                quads,
                spheres: vec![Sphere::new(Vec3::new(0.0, 1.0, 0.0), 1.0, 2)],
                ..Default::default()
            },
            materials: vec![
                Material::diffuse(0.8, 0.8, 0.8),
                Material::diffuse(0.0, 0.0, 0.0),
                Material::Dielectric { ior: 1.5 },
            ],
            textures: vec![],
            lights,
        }
    }
}
