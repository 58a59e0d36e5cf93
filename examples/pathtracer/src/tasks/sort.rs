//! SORT: slide 75 coloured cubes so that each colour group fills its own band.
//!
//! Seen from above under a constant sky, so only what the task needs is rendered: colour,
//! position and the cubes' soft contact shadows. The cubes move every evaluation, so their
//! small BVH is rebuilt per render (cheap beside the render: benches/render.rs times it).

use glam::{Vec3, Vec3A};

use super::{param, Aim, Scenario, Shot};
use crate::render::rng::hash_unit;
use crate::render::{AaBox, BoxSet, Camera, Geometry, Lights, Material, Quad, Scene};

/// Number of cubes (three groups of 25).
pub const CUBES: usize = 75;
const GROUP: usize = 25;
/// Half the cube's edge, world units; theta in [0, 1] spans [-2.5, 2.5].
const HALF: f32 = 0.15;
const EXTENT: f32 = 5.0;

/// Straight down; image up is -z, so image right is +x.
pub(super) const CAMERA: Shot =
    Shot::new(EYE, Aim::Along(Vec3::NEG_Y), Vec3::NEG_Z, 26.3, (64, 64));
const EYE: Vec3 = Vec3::new(0.0, 12.0, 0.0);

/// The SORT task.
pub struct Sort;

impl Scenario for Sort {
    fn scene(&self, theta: &[f64], camera: Camera) -> Scene {
        let boxes: Vec<AaBox> = (0..CUBES)
            .map(|k| {
                let c = Vec3A::new(
                    EXTENT * (param(theta, 2 * k) - 0.5),
                    HALF,
                    EXTENT * (param(theta, 2 * k + 1) - 0.5),
                );
                AaBox {
                    min: c - Vec3A::splat(HALF),
                    max: c + Vec3A::splat(HALF),
                    material: 1 + (k / GROUP) as u32,
                }
            })
            .collect();
        Scene {
            camera,
            geometry: Geometry {
                quads: vec![Quad::centered(
                    Vec3::ZERO,
                    Vec3::Z * 10.0,
                    Vec3::X * 10.0,
                    0,
                )],
                box_set: Some(BoxSet::new(&boxes)),
                ..Default::default()
            },
            materials: vec![
                Material::grey(0.6),
                Material::diffuse(0.85, 0.1, 0.08),
                Material::diffuse(0.1, 0.7, 0.12),
                Material::diffuse(0.08, 0.15, 0.85),
            ],
            textures: vec![],
            lights: Lights {
                environment: Vec3A::splat(1.0),
                environment_nee: false,
                ..Default::default()
            },
        }
    }

    /// Every cube at an independent pseudo-random place in [0.05, 0.95]^2 (fixed hash).
    fn start(&self) -> Vec<f64> {
        (0..2 * CUBES)
            .map(|i| 0.05 + 0.9 * hash_unit(0x5027, i as u64))
            .collect()
    }

    /// Group g (cubes 25g .. 25g + 24) on a 5 x 5 grid in the band x in [g/3, (g+1)/3].
    fn target(&self) -> Vec<f64> {
        let mut theta = Vec::with_capacity(2 * CUBES);
        for k in 0..CUBES {
            let (g, j) = (k / GROUP, k % GROUP);
            let (col, row) = (j % 5, j / 5);
            theta.push((5 * g + col) as f64 / 15.0 + 0.5 / 15.0);
            theta.push((row as f64 + 0.5) / 5.0);
        }
        theta
    }
}
