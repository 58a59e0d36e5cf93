//! CAUSTIC: find a light outside the view from the caustic it casts through a glass ball.
//! The ball plugs the hole of an opaque plate, so the caustic is the only light from the
//! emitter that reaches the ground the camera sees.

use glam::Vec3;

use super::{param, Aim, Scenario, Shot};
use crate::render::{Camera, Geometry, Lights, Material, Quad, Scene, Sphere};

/// The CAUSTIC task.
pub struct Caustic;

// The design and the measurements behind it: docs/tasks.md, CAUSTIC.

/// Height of the emitter, above the plate; theta in [0, 1]^2 spans x, z in
/// [-LIGHT_RANGE, LIGHT_RANGE].
const LIGHT_HEIGHT: f32 = 3.0;
const LIGHT_RANGE: f32 = 2.0;
/// Side of the square emitter: large and dim, so the caustic is wide and smooth at 32 spp.
const LAMP_SIZE: f32 = 1.5;
const RADIANCE: f32 = 5.0;
/// The opaque plate between the emitter and the ground, and its hole's half-side: the hole
/// (|x|, |z| <= HOLE) is inscribed in the sphere's cross-section at PLATE_Y (radius
/// sqrt(1 - 0.5^2) = 0.866 > 0.6 sqrt(2)), so the sphere plugs it.
const PLATE_Y: f32 = 1.5;
const HOLE: f32 = 0.6;
const PLATE_EXTENT: f32 = 8.0;
const PLATE_ALBEDO: f32 = 0.0;
/// Radiance of the plate's underside (a dim fill light, independent of theta).
const FILL: f32 = 0.3;
/// Camera under the plate, looking at the ground below the sphere.
pub(super) const CAMERA: Shot = Shot::new(EYE, Aim::At(Vec3::ZERO), Vec3::Y, 45.0, (128, 96));
const EYE: Vec3 = Vec3::new(0.0, 1.4, 4.5);

impl Scenario for Caustic {
    fn scene(&self, theta: &[f64], camera: Camera) -> Scene {
        let lamp = Vec3::new(
            -LIGHT_RANGE + 2.0 * LIGHT_RANGE * param(theta, 0),
            LIGHT_HEIGHT,
            -LIGHT_RANGE + 2.0 * LIGHT_RANGE * param(theta, 1),
        );
        // Ground facing up (z x x = +y).
        let mut quads = vec![Quad::centered(
            Vec3::ZERO,
            Vec3::Z * 16.0,
            Vec3::X * 16.0,
            0,
        )];
        let mut lights = Lights::default();
        // The plate: an opaque square [-8, 8]^2 at PLATE_Y with a square hole of half-side
        // HOLE around the vertical through the sphere's centre, inscribed in the sphere's
        // cross-section there, so every ray through the hole enters the glass.
        let (e, h, y) = (PLATE_EXTENT, HOLE, PLATE_Y);
        for (lo, hi) in [
            (Vec3::new(-e, y, -e), Vec3::new(e, y, -h)),
            (Vec3::new(-e, y, h), Vec3::new(e, y, e)),
            (Vec3::new(-e, y, -h), Vec3::new(-h, y, h)),
            (Vec3::new(h, y, -h), Vec3::new(e, y, h)),
        ] {
            // Facing down (x x z = -y): the plate's underside glows dimly (a fill light).
            lights.add_area(
                &mut quads,
                Quad::new(lo, Vec3::X * (hi.x - lo.x), Vec3::Z * (hi.z - lo.z), 1),
                Vec3::splat(FILL),
            );
        }
        // The emitter, facing down (x x z = -y): its light reaches the space under the plate
        // only through the sphere.
        lights.add_area(
            &mut quads,
            Quad::centered(lamp, Vec3::X * LAMP_SIZE, Vec3::Z * LAMP_SIZE, 1),
            Vec3::splat(RADIANCE),
        );
        Scene {
            camera,
            geometry: Geometry {
                quads,
                spheres: vec![Sphere::new(Vec3::new(0.0, 1.0, 0.0), 1.0, 2)],
                ..Default::default()
            },
            materials: vec![
                Material::grey(0.8),
                Material::grey(PLATE_ALBEDO),
                Material::Dielectric { ior: 1.5 },
            ],
            textures: vec![],
            lights,
        }
    }

    fn start(&self) -> Vec<f64> {
        vec![0.5, 0.9]
    }

    fn target(&self) -> Vec<f64> {
        vec![0.3, 0.35]
    }
}
