//! TEXTURE (supplemental Sec. 3): recover a 128 x 128 RGB texture (49,152 parameters) seen
//! on a plane under a constant sky, from a flat grey start. Plateau-free by design: it shows
//! the estimator at a very high dimension.

use std::f64::consts::TAU;

use glam::{Vec3, Vec3A};

use super::{Aim, Scenario, Shot};
use crate::render::{Camera, Geometry, Lights, Material, Quad, Scene, Texture};

/// Texture side, in texels.
pub const SIDE: u32 = 128;
/// Parameters: RGB per texel.
const DIM: usize = (3 * SIDE * SIDE) as usize;

/// From z = DISTANCE the plane [-1, 1]^2 at z = 0 exactly fills a SIDE x SIDE view, a texel
/// per pixel: the field of view is 2 atan(1 / DISTANCE) (a literal, as `atan` is not `const`;
/// a test checks it).
pub(super) const CAMERA: Shot =
    Shot::new(EYE, Aim::Along(Vec3::NEG_Z), Vec3::Y, HFOV, (SIDE, SIDE));
const DISTANCE: f32 = 10.0;
const EYE: Vec3 = Vec3::new(0.0, 0.0, DISTANCE);
const HFOV: f64 = 11.421186274999286;

/// The TEXTURE task.
pub struct TextureTask;

/// The reference texture at (u, v) in [0, 1]^2: diagonal colour waves, a checkerboard and
/// concentric rings, so every channel has edges and gradients at several scales.
fn reference(u: f64, v: f64) -> [f64; 3] {
    let waves = 0.5 + 0.5 * (TAU * (2.0 * u + v)).sin();
    let checker = if ((8.0 * u) as i32 + (8.0 * v) as i32) % 2 == 0 {
        0.85
    } else {
        0.15
    };
    let r = ((u - 0.5).powi(2) + (v - 0.5).powi(2)).sqrt();
    let rings = 0.5 + 0.5 * (TAU * 5.0 * r).cos();
    [
        0.1 + 0.8 * waves,
        0.5 * checker + 0.4 * rings,
        0.9 - 0.7 * waves * rings,
    ]
}

impl Scenario for TextureTask {
    fn scene(&self, theta: &[f64], camera: Camera) -> Scene {
        let texture = if theta.len() == DIM {
            Texture::from_rgb(SIDE, SIDE, theta)
        } else {
            Texture::from_rgb(1, 1, &[0.0, 0.0, 0.0])
        };
        Scene {
            camera,
            geometry: Geometry {
                // Corner top-left, u to the right, v down: uv = (column, row) fractions.
                quads: vec![Quad::new(
                    Vec3::new(-1.0, 1.0, 0.0),
                    Vec3::X * 2.0,
                    Vec3::NEG_Y * 2.0,
                    0,
                )],
                ..Default::default()
            },
            materials: vec![Material::Diffuse {
                albedo: Vec3A::ONE,
                texture: Some(0),
            }],
            textures: vec![texture],
            lights: Lights {
                environment: Vec3A::splat(1.0),
                environment_nee: false,
                ..Default::default()
            },
        }
    }

    fn start(&self) -> Vec<f64> {
        vec![0.5; DIM]
    }

    /// Texel (i, j) sampled at its centre, rows top to bottom, RGB interleaved.
    fn target(&self) -> Vec<f64> {
        let n = SIDE as f64;
        let mut theta = Vec::with_capacity(DIM);
        for j in 0..SIDE {
            for i in 0..SIDE {
                theta.extend(reference((i as f64 + 0.5) / n, (j as f64 + 0.5) / n));
            }
        }
        theta
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_of_view_fits_the_plane() {
        assert_eq!(HFOV, 2.0 * (1.0 / DISTANCE as f64).atan().to_degrees());
    }
}
