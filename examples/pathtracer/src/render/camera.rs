//! Pinhole camera.

use glam::{Vec3, Vec3A};

/// A pinhole camera with a box pixel filter (uniform jitter inside the pixel).
///
/// The image's right is `view direction x up`, its top is `up` (orthogonalised): the image is
/// never mirrored, whatever the handedness of the scene's coordinates.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    origin: Vec3A,
    forward: Vec3A,
    /// Right vector scaled so that one image width spans the horizontal field of view.
    right: Vec3A,
    /// Up vector scaled with the same pixel pitch as `right` (square pixels).
    up: Vec3A,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera at `position` looking along `direction`, `up` roughly vertical, horizontal
    /// field of view `hfov_degrees`, `width` x `height` pixels.
    pub fn new(
        position: Vec3,
        direction: Vec3,
        up: Vec3,
        hfov_degrees: f64,
        width: u32,
        height: u32,
    ) -> Self {
        let forward = Vec3A::from(direction).normalize();
        let right = forward.cross(Vec3A::from(up)).normalize();
        let true_up = right.cross(forward);
        let half_width = (0.5 * hfov_degrees.to_radians()).tan() as f32;
        let half_height = half_width * height as f32 / width as f32;
        Self {
            origin: position.into(),
            forward,
            right: right * half_width,
            up: true_up * half_height,
            width,
            height,
        }
    }

    /// A camera at `position` looking at `target`.
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        hfov_degrees: f64,
        width: u32,
        height: u32,
    ) -> Self {
        Self::new(position, target - position, up, hfov_degrees, width, height)
    }

    /// The camera's position.
    pub fn origin(&self) -> Vec3A {
        self.origin
    }

    /// Unit view direction.
    pub fn forward(&self) -> Vec3A {
        self.forward
    }

    /// Unit image-up direction (orthogonal to [`Camera::forward`]).
    pub fn up(&self) -> Vec3A {
        self.up.normalize()
    }

    /// Horizontal field of view in degrees.
    pub fn hfov_degrees(&self) -> f64 {
        2.0 * (self.right.length() as f64).atan().to_degrees()
    }

    /// Unit direction of the ray through pixel (`x`, `y`) (row 0 at the top) at sub-pixel
    /// offset (`jx`, `jy`) in [0, 1)^2.
    #[inline(always)]
    pub fn direction(&self, x: u32, y: u32, jx: f32, jy: f32) -> Vec3A {
        let sx = 2.0 * (x as f32 + jx) / self.width as f32 - 1.0;
        let sy = 1.0 - 2.0 * (y as f32 + jy) / self.height as f32;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_is_forward_cross_up_and_not_mirrored() {
        // SHADOW's camera: looking along -x with +z up, so the image right must be +y.
        let cam = Camera::new(
            Vec3::new(17.658, 0.0, 0.0),
            Vec3::NEG_X,
            Vec3::Z,
            39.597755,
            256,
            192,
        );
        let right_edge = cam.direction(255, 96, 1.0, 0.0);
        let top_edge = cam.direction(128, 0, 0.0, 0.0);
        assert!(right_edge.y > 0.3 && right_edge.x < 0.0);
        assert!(top_edge.z > 0.2);
        // Half the horizontal field of view at the right edge.
        let angle = right_edge.dot(Vec3A::NEG_X).acos().to_degrees();
        assert!((angle - 39.597755 / 2.0).abs() < 0.05, "{angle}");
    }
}
