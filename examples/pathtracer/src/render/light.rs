//! Light sources and their sampling for next-event estimation.

use glam::{Vec3, Vec3A};

use super::geometry::Quad;

/// An isotropic point light; `intensity` is radiant intensity (W/sr per channel), so a
/// surface at distance d receives irradiance `intensity * cos / d^2`.
#[derive(Clone, Copy, Debug)]
pub struct PointLight {
    /// Position.
    pub position: Vec3A,
    /// Radiant intensity.
    pub intensity: Vec3A,
}

impl PointLight {
    /// A point light at `position` with RGB `intensity`.
    pub fn new(position: Vec3, intensity: Vec3) -> Self {
        Self {
            position: position.into(),
            intensity: intensity.into(),
        }
    }
}

/// The scene's lights. Area lights are emitting quads of the geometry (so rays can hit them);
/// this holds their indices.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    /// Point lights (reached by next-event estimation only: a ray never hits a point).
    pub points: Vec<PointLight>,
    /// Indices of emitting quads in `Geometry::quads`; quad `areas[k]` has `light == k`.
    pub areas: Vec<u32>,
    /// Constant environment radiance for rays that leave the scene (zero: none).
    pub environment: Vec3A,
    /// Whether the environment is also sampled by next-event estimation (MIS-weighted
    /// against the BSDF sample). For a constant environment lighting Lambertian surfaces,
    /// cosine BSDF sampling is already proportional to the unoccluded integrand, so this only
    /// trades a shadow ray for less visibility noise.
    pub environment_nee: bool,
}

/// A point sampled on an area light, seen from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct AreaSample {
    /// Unit direction from the shading point to the light point.
    pub dir: Vec3A,
    /// Distance to the light point.
    pub dist: f32,
    /// Radiance emitted towards the shading point.
    pub radiance: Vec3A,
    /// Solid-angle density of this sample, including the choice of the light.
    pub pdf: f32,
}

impl Lights {
    /// Adds an emitting quad to `quads` and registers it as an area light.
    pub fn add_area(&mut self, quads: &mut Vec<Quad>, mut quad: Quad, radiance: Vec3) {
        quad.emission = radiance.into();
        quad.light = self.areas.len() as u32;
        self.areas.push(quads.len() as u32);
        quads.push(quad);
    }

    /// Picks an area light uniformly (`u_pick`) and a point uniformly on it (`u1`, `u2`).
    /// None when there is no light or it faces away.
    #[inline]
    pub fn sample_area(
        &self,
        quads: &[Quad],
        p: Vec3A,
        u_pick: f32,
        u1: f32,
        u2: f32,
    ) -> Option<AreaSample> {
        let n = self.areas.len();
        if n == 0 {
            return None;
        }
        let k = ((u_pick * n as f32) as usize).min(n - 1);
        let q = &quads[self.areas[k] as usize];
        let to = q.point(u1, u2) - p;
        let dist2 = to.length_squared();
        let dist = dist2.sqrt();
        let dir = to / dist;
        let cos_l = -q.normal.dot(dir);
        // Written so that NaNs (a degenerate quad or a point on the light) reject the sample.
        let usable = cos_l > 1e-7 && dist > 0.0;
        if !usable {
            return None;
        }
        Some(AreaSample {
            dir,
            dist,
            radiance: q.emission,
            pdf: dist2 / (cos_l * q.area * n as f32),
        })
    }

    /// Solid-angle density with which [`Lights::sample_area`] would pick the point `hit` on
    /// the quad `q` from `p` along unit `dir` (for MIS weights of BSDF-sampled hits).
    #[inline]
    pub fn area_pdf(&self, q: &Quad, p: Vec3A, hit: Vec3A, dir: Vec3A) -> f32 {
        let cos_l = -q.normal.dot(dir);
        if cos_l <= 0.0 || self.areas.is_empty() {
            return 0.0;
        }
        (hit - p).length_squared() / (cos_l * q.area * self.areas.len() as f32)
    }
}
