//! TEXTURE (supplemental Sec. 3): recover a 128 x 128 RGB texture (49,152 parameters) seen
//! on a plane under a constant sky, from a flat grey start. Plateau-free by design: it shows
//! the estimator at a very high dimension.

use std::f64::consts::TAU;

use glam::{Vec3, Vec3A};

#[cfg(test)]
use super::View;
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
    /// Each pixel's texels: the corners of the pixel are traced through the camera onto the
    /// textured quad, and the pixel's channel `c` depends on channel `c` of every texel the
    /// bilinear lookup can reach from the UV rectangle they span (the rectangle, widened to
    /// the lookup's neighbours). A pixel that misses the quad depends on nothing. Derived
    /// from the scene, so a changed camera or resolution changes the pattern with it.
    fn footprint(&self, camera: Camera) -> Option<plateau_free::vector::Sparsity> {
        let scene = self.scene(&[], camera);
        let (w, h) = (camera.width as usize, camera.height as usize);
        let side = SIDE as f32;
        let texels = |lo: f32, hi: f32| {
            // The lookup at x reads texels floor(x) and floor(x) + 1, x = u * SIDE - 0.5,
            // clamped onto the texture.
            let first = (lo * side - 0.5).floor().clamp(0.0, side - 1.0) as usize;
            let last = ((hi * side - 0.5).floor() + 1.0).clamp(0.0, side - 1.0) as usize;
            first..=last
        };
        let pattern = plateau_free::vector::Sparsity::from_fn(3 * w * h, DIM, |value, row| {
            let (pixel, channel) = (value / 3, value % 3);
            let (x, y) = ((pixel % w) as u32, (pixel / w) as u32);
            let mut uv = Vec::with_capacity(4);
            for (jx, jy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let d = camera.direction(x, y, jx, jy);
                if let Some((_, hit)) = scene.geometry.intersect(camera.origin(), d, f32::INFINITY)
                {
                    uv.push(hit.uv);
                }
            }
            if uv.is_empty() {
                return;
            }
            let fold = |f: fn(f32, f32) -> f32, init: f32, pick: fn(&glam::Vec2) -> f32| {
                uv.iter().map(pick).fold(init, f)
            };
            let us = texels(
                fold(f32::min, f32::MAX, |p| p.x),
                fold(f32::max, f32::MIN, |p| p.x),
            );
            let vs = texels(
                fold(f32::min, f32::MAX, |p| p.y),
                fold(f32::max, f32::MIN, |p| p.y),
            );
            for v in vs {
                for u in us.clone() {
                    row.push(3 * (v * SIDE as usize + u) + channel);
                }
            }
        });
        pattern.ok()
    }

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

    /// The footprint derived from the scene: every pixel's channel on the same channel of the
    /// texel under the pixel's centre and of at most its 3 x 3 neighbours (a texel per pixel,
    /// read bilinearly); at half the resolution, on the 4 x 4 texels under it and their rim.
    #[test]
    fn the_footprint_is_the_texels_under_each_pixel() {
        let task = crate::tasks::by_name("texture").unwrap();
        let pattern = task.footprint(Default::default()).unwrap();
        let side = SIDE as usize;
        assert_eq!((pattern.outputs(), pattern.params()), (DIM, DIM));
        assert!(pattern.max_row() <= 9, "{}", pattern.max_row());
        for (x, y, c) in [(0, 0, 0), (5, 7, 1), (127, 127, 2), (64, 3, 0)] {
            let value = 3 * (y * side + x) + c;
            let row = pattern.row(value);
            assert!(
                row.contains(&(3 * (y * side + x) + c)),
                "pixel ({x}, {y}): {row:?}"
            );
            assert!(row.iter().all(|j| j % 3 == c));
        }
        let half = View {
            scale: Some(0.5),
            ..Default::default()
        };
        let coarse = task.footprint(half).unwrap();
        assert_eq!(coarse.outputs(), DIM / 4);
        assert!(
            coarse.max_row() <= 36 && coarse.max_row() >= 16,
            "{}",
            coarse.max_row()
        );
    }

    #[test]
    fn field_of_view_fits_the_plane() {
        assert_eq!(HFOV, 2.0 * (1.0 / DISTANCE as f64).atan().to_degrees());
    }
}
