//! Surface scattering: Lambertian diffuse (optionally textured) and smooth dielectric.

use glam::{Vec2, Vec3A};

/// How a surface scatters light.
#[derive(Clone, Copy, Debug)]
pub enum Material {
    /// Lambertian reflector; `texture` (index into the scene's textures), when present,
    /// replaces `albedo` and is looked up by the surface's uv.
    Diffuse {
        /// Reflectance per channel, in [0, 1].
        albedo: Vec3A,
        /// Optional texture index.
        texture: Option<u32>,
    },
    /// Smooth glass-like interface: Fresnel-weighted choice of mirror reflection and refraction.
    Dielectric {
        /// Index of refraction inside (the normal points outside, to IOR 1).
        ior: f32,
    },
}

impl Material {
    /// An untextured Lambertian material.
    pub fn diffuse(r: f32, g: f32, b: f32) -> Self {
        Material::Diffuse {
            albedo: Vec3A::new(r, g, b),
            texture: None,
        }
    }

    /// An untextured grey Lambertian material: the walls, floors and black backs of lights.
    pub fn grey(albedo: f32) -> Self {
        Material::diffuse(albedo, albedo, albedo)
    }
}

/// An RGB texture, sampled bilinearly with clamp-to-edge; v = 0 is the first row.
#[derive(Clone, Debug)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Vec<Vec3A>,
}

impl Texture {
    /// From `width * height * 3` values (row-major, RGB), each clamped to [0, 1] so that a
    /// parameter vector that left the box still renders a physical reflectance.
    pub fn from_rgb(width: u32, height: u32, rgb: &[f64]) -> Self {
        let texels = rgb
            .chunks_exact(3)
            .map(|c| {
                let f = |x: f64| {
                    if x.is_finite() {
                        x.clamp(0.0, 1.0) as f32
                    } else {
                        0.0
                    }
                };
                Vec3A::new(f(c[0]), f(c[1]), f(c[2]))
            })
            .collect();
        Self {
            width,
            height,
            texels,
        }
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texels, row-major from the first row (v = 0), already clamped to [0, 1].
    pub fn texels(&self) -> &[Vec3A] {
        &self.texels
    }

    /// Bilinear lookup at `uv` in [0, 1]^2 (texel centres at half-integers).
    #[inline]
    pub fn sample(&self, uv: Vec2) -> Vec3A {
        let x = (uv.x * self.width as f32 - 0.5).clamp(0.0, (self.width - 1) as f32);
        let y = (uv.y * self.height as f32 - 0.5).clamp(0.0, (self.height - 1) as f32);
        let (x0, y0) = (x as u32, y as u32);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let at = |xx: u32, yy: u32| self.texels[(yy * self.width + xx) as usize];
        let top = at(x0, y0).lerp(at(x1, y0), fx);
        let bottom = at(x0, y1).lerp(at(x1, y1), fx);
        top.lerp(bottom, fy)
    }
}

/// An orthonormal basis (t, b) completing the unit vector `n` (Duff et al. 2017, branchless).
#[inline(always)]
pub fn basis(n: Vec3A) -> (Vec3A, Vec3A) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3A::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A cosine-distributed direction about the unit normal `n` (pdf = cos / pi).
#[inline(always)]
pub fn sample_cosine(n: Vec3A, u1: f32, u2: f32) -> Vec3A {
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let (s, c) = phi.sin_cos();
    let (t, b) = basis(n);
    let z = (1.0 - u1).max(0.0).sqrt();
    (r * c * t + r * s * b + z * n).normalize()
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface; `cos_i` > 0 on the
/// incident side, `eta` = incident IOR / transmitted IOR. Returns (reflectance, cos_t), with
/// reflectance 1 under total internal reflection.
#[inline(always)]
pub fn fresnel(cos_i: f32, eta: f32) -> (f32, f32) {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// One scattering event at a smooth dielectric: returns the new direction, the radiance
/// factor (eta^2 on refraction, because radiance is compressed into the denser medium), and
/// whether the ray went through.
#[inline(always)]
pub fn scatter_dielectric(d: Vec3A, n: Vec3A, ior: f32, u: f32) -> (Vec3A, f32, bool) {
    let cos = d.dot(n);
    let (facing, eta) = if cos < 0.0 { (n, 1.0 / ior) } else { (-n, ior) };
    let cos_i = cos.abs();
    let (reflectance, cos_t) = fresnel(cos_i, eta);
    if u < reflectance {
        (d + 2.0 * cos_i * facing, 1.0, false)
    } else {
        let t = eta * d + (eta * cos_i - cos_t) * facing;
        (t.normalize(), eta * eta, true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_normal_incidence_and_tir() {
        let (r, _) = fresnel(1.0, 1.0 / 1.5);
        assert!((r - 0.04).abs() < 1e-4, "{r}");
        let (r, _) = fresnel(0.1, 1.5);
        assert_eq!(r, 1.0);
    }

    #[test]
    fn basis_is_orthonormal() {
        for n in [
            Vec3A::X,
            Vec3A::NEG_Z,
            Vec3A::new(0.3, -0.5, 0.8).normalize(),
        ] {
            let (t, b) = basis(n);
            assert!(t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6 && t.dot(b).abs() < 1e-6);
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn refraction_obeys_snell() {
        let d = Vec3A::new(0.5, -(0.75f32).sqrt(), 0.0);
        let (t, scale, through) = scatter_dielectric(d, Vec3A::Y, 1.5, 0.99);
        assert!(through);
        assert!((t.x - 0.5 / 1.5).abs() < 1e-5, "{t}");
        assert!((scale - 1.0 / 2.25).abs() < 1e-6);
    }

    #[test]
    fn bilinear_texture_interpolates() {
        let tex = Texture::from_rgb(2, 1, &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        assert!((tex.sample(Vec2::new(0.5, 0.5)).x - 0.5).abs() < 1e-6);
        assert_eq!(tex.sample(Vec2::new(0.0, 0.0)).x, 0.0);
        assert_eq!(tex.sample(Vec2::new(1.0, 1.0)).x, 1.0);
    }
}
