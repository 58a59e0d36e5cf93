//! Unidirectional path tracing with next-event estimation and multiple importance sampling.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3A;
use rayon::prelude::*;

use super::film::Image;
use super::lanes::QuadLanes;
use super::material::{sample_cosine, scatter_dielectric, Material};
use super::rng::Sampler;
use super::Scene;

/// What to render besides the scene.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Samples (camera paths) per pixel; 0 renders as 1.
    pub spp: u32,
    /// Seed of every random number of the image.
    pub seed: u64,
    /// Longest path in segments, Mitsuba's convention: 1 shows emitters only, 2 is direct
    /// lighting, each further unit adds one bounce.
    pub max_depth: u32,
    /// Next-event estimation on (the default). Off, only BSDF sampling finds light, and point
    /// lights (which no ray can hit) go dark: a reference for tests.
    pub nee: bool,
}

impl Settings {
    /// NEE on.
    pub fn new(spp: u32, seed: u64, max_depth: u32) -> Self {
        Self {
            spp,
            seed,
            max_depth,
            nee: true,
        }
    }
}

/// Renders `scene`: a pure function of (scene, settings). Rows run in parallel with rayon,
/// but each sample's random numbers come from (seed, pixel, sample) alone and each pixel sums
/// its samples in order, so the bits do not depend on the thread count.
pub fn render(scene: &Scene, settings: &Settings) -> Image {
    let camera = &scene.camera;
    let (width, height) = (camera.width, camera.height);
    let spp = settings.spp.max(1);
    let mut image = Image::new(width, height);
    let origin = camera.origin();
    // Packing pays from a full group of four on: with one quad (SHADOW, SORT, TEXTURE) the
    // padded lanes made those renders 10-25 % slower. Either way the bits are the same.
    let quads = &scene.geometry.quads;
    let lanes = (quads.len() >= 4).then(|| QuadLanes::pack(quads));
    let lanes = lanes.as_deref();
    image
        .data
        .par_chunks_mut(3 * width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            let y = y as u32;
            for x in 0..width {
                let pixel = y * width + x;
                let mut sum = Vec3A::ZERO;
                for s in 0..spp {
                    let mut rng = Sampler::new(settings.seed, pixel, s);
                    let (jx, jy) = rng.next_2d();
                    let d = camera.direction(x, y, jx, jy);
                    let l = trace(scene, lanes, origin, d, &mut rng, settings);
                    // A NaN or infinity from a degenerate configuration must never reach the
                    // image: drop that sample (a zero-contribution sample, still counted).
                    if l.is_finite() {
                        sum += l;
                    }
                }
                let v = sum / spp as f32;
                let i = 3 * x as usize;
                row[i] = v.x;
                row[i + 1] = v.y;
                row[i + 2] = v.z;
            }
        });
    image
}

/// Veach's power heuristic (beta = 2) weight of the strategy with density `a` against `b`.
#[inline(always)]
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    let w = a2 / (a2 + b2);
    if w.is_finite() {
        w
    } else if a > b {
        1.0
    } else {
        0.0
    }
}

/// Distance to push a new ray's origin off its surface: relative to the coordinates'
/// magnitude, since f32 spacing grows with them.
#[inline(always)]
fn offset(p: Vec3A) -> f32 {
    1e-4 * (1.0 + p.abs().max_element())
}

/// Radiance arriving at `o` from direction `-d`; `lanes` are the scene's quads packed for
/// 4-wide tests (the same answers as testing them one by one, bit for bit).
#[inline]
fn trace(
    scene: &Scene,
    lanes: Option<&[QuadLanes]>,
    mut o: Vec3A,
    mut d: Vec3A,
    rng: &mut Sampler,
    s: &Settings,
) -> Vec3A {
    let geo = &scene.geometry;
    let lights = &scene.lights;
    let env = lights.environment;
    let has_env = env != Vec3A::ZERO;
    let env_nee = s.nee && lights.environment_nee && has_env;

    let mut radiance = Vec3A::ZERO;
    let mut beta = Vec3A::ONE;
    let mut segments = 1u32;
    // The last scattering was a delta (or the camera): emission found by it cannot have
    // been found by NEE, so it counts with full weight (this is what makes caustics).
    let mut specular = true;
    let mut prev_p = o;
    let mut prev_pdf = 0.0f32;

    loop {
        let Some((_, hit)) = geo.intersect_in(lanes, o, d, f32::INFINITY) else {
            if has_env {
                let w = if specular || !env_nee {
                    1.0
                } else {
                    // Both strategies are cosine-distributed about the same normal.
                    power_heuristic(prev_pdf, prev_pdf)
                };
                radiance += beta * env * w;
            }
            break;
        };

        if hit.emission != Vec3A::ZERO {
            let w = if specular || !s.nee {
                1.0
            } else {
                let k = hit.light as usize;
                let light_pdf = lights.areas.get(k).map_or(0.0, |&q| {
                    lights.area_pdf(&geo.quads[q as usize], prev_p, hit.p, d)
                });
                power_heuristic(prev_pdf, light_pdf)
            };
            radiance += beta * hit.emission * w;
        }

        if segments >= s.max_depth {
            break;
        }

        match scene.materials[hit.material as usize] {
            Material::Diffuse { albedo, texture } => {
                let albedo = match texture {
                    Some(t) => scene.textures[t as usize].sample(hit.uv),
                    None => albedo,
                };
                let n = if hit.n.dot(d) < 0.0 { hit.n } else { -hit.n };
                let p = hit.p + offset(hit.p) * n;
                if s.nee {
                    let f = beta * albedo * FRAC_1_PI;
                    for light in &lights.points {
                        let to = light.position - p;
                        let dist2 = to.length_squared();
                        let dist = dist2.sqrt();
                        let wi = to / dist;
                        let cos = n.dot(wi);
                        if cos > 0.0 && !geo.occluded_in(lanes, p, wi, dist * (1.0 - 1e-4)) {
                            radiance += f * light.intensity * (cos / dist2);
                        }
                    }
                    if !lights.areas.is_empty() {
                        let u_pick = rng.next_f32();
                        let (u1, u2) = rng.next_2d();
                        if let Some(ls) = lights.sample_area(&geo.quads, p, u_pick, u1, u2) {
                            let cos = n.dot(ls.dir);
                            if cos > 0.0
                                && !geo.occluded_in(lanes, p, ls.dir, ls.dist * (1.0 - 1e-4))
                            {
                                let w = power_heuristic(ls.pdf, cos * FRAC_1_PI);
                                radiance += f * ls.radiance * (cos * w / ls.pdf);
                            }
                        }
                    }
                    if env_nee {
                        let (u1, u2) = rng.next_2d();
                        let wi = sample_cosine(n, u1, u2);
                        if n.dot(wi) > 0.0 && !geo.occluded_in(lanes, p, wi, f32::INFINITY) {
                            // f * L * cos / pdf with pdf = cos / pi, times the MIS weight.
                            let pdf = n.dot(wi) * FRAC_1_PI;
                            radiance += beta * albedo * env * power_heuristic(pdf, pdf);
                        }
                    }
                }
                let (u1, u2) = rng.next_2d();
                let wi = sample_cosine(n, u1, u2);
                let cos = n.dot(wi);
                if cos <= 0.0 {
                    break;
                }
                beta *= albedo;
                prev_pdf = cos * FRAC_1_PI;
                prev_p = p;
                specular = false;
                o = p;
                d = wi;
            }
            Material::Dielectric { ior } => {
                let (wi, scale, _) = scatter_dielectric(d, hit.n, ior, rng.next_f32());
                beta *= scale;
                let side = if wi.dot(hit.n) > 0.0 { hit.n } else { -hit.n };
                o = hit.p + offset(hit.p) * side;
                d = wi;
                specular = true;
            }
        }

        segments += 1;
        if segments > 3 {
            let q = beta.max_element().min(0.95);
            if rng.next_f32() >= q {
                break;
            }
            beta /= q;
        }
    }
    radiance
}
