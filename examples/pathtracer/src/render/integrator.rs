//! Unidirectional path tracing with next-event estimation and multiple importance sampling.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3A;
use rayon::prelude::*;

use super::film::Image;
use super::geometry::{Prim, Surface};
use super::lanes::QuadLanes;
use super::last_segment::LastHit;
use super::material::{sample_cosine, scatter_dielectric, Material};
use super::path_lanes::RayPack;
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

/// Camera paths of a pixel traced together, taking turns segment by segment: each path is a
/// long chain of dependent square roots and divisions, and independent chains side by side
/// let the CPU overlap their latencies; their rays meet the spheres and quads four paths at
/// once ([`RayPack`]), two packs a turn.
const IN_FLIGHT: u32 = 8;

/// Renders `scene`: a pure function of (scene, settings). Rows run in parallel with rayon,
/// but each sample's random numbers come from (seed, pixel, sample) alone and each pixel sums
/// its samples in order, so the bits do not depend on the thread count.
pub fn render(scene: &Scene, settings: &Settings) -> Image {
    render_with::<false>(scene, settings).0
}

/// The work of a render: camera paths traced and rays cast.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Work {
    /// Camera paths (samples): pixels times samples per pixel.
    pub paths: u64,
    /// Rays cast: closest-hit queries, last-segment queries and shadow rays.
    pub rays: u64,
}

/// [`render`] that also counts its [`Work`]; the image is the same, bit for bit.
///
/// ```
/// use pathtracer::render::{render, render_counted, Settings};
/// let scene = pathtracer::tasks::by_name("shadow").unwrap();
/// let scene = scene.scene(&scene.target(), pathtracer::tasks::View { scale: Some(0.1), ..Default::default() });
/// let settings = Settings::new(2, 0, 6);
/// let (image, work) = render_counted(&scene, &settings);
/// assert_eq!(image.data, render(&scene, &settings).data);
/// assert_eq!(work.paths, 2 * (scene.camera.width * scene.camera.height) as u64);
/// assert!(work.rays >= 2 * work.paths);
/// ```
pub fn render_counted(scene: &Scene, settings: &Settings) -> (Image, Work) {
    render_with::<true>(scene, settings)
}

/// [`render`], counting the rays when `COUNT` (a separate compilation of the render loop, so
/// that the uncounted one is unchanged).
fn render_with<const COUNT: bool>(scene: &Scene, settings: &Settings) -> (Image, Work) {
    let camera = &scene.camera;
    let (width, height) = (camera.width, camera.height);
    let mut image = Image::new(width, height);
    // Packing pays from three quads on (CUP's three); with one quad (SHADOW, SORT, TEXTURE)
    // the padded lanes cost more than they save (see benches/render.rs). Either way the bits
    // are the same.
    let quads = &scene.geometry.quads;
    let lanes = (quads.len() >= 3).then(|| QuadLanes::pack(quads));
    let tracer = Tracer::<COUNT>::new(scene, lanes.as_deref(), settings);
    let rays = image
        .data
        .par_chunks_mut(3 * width as usize)
        .enumerate()
        .map(|(y, row)| tracer.row(y as u32, row))
        .sum();
    let paths = u64::from(width) * u64::from(height) * u64::from(settings.spp.max(1));
    (image, Work { paths, rays })
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

/// The scene and settings a path needs at every segment, and what follows from them.
struct Tracer<'a, const COUNT: bool> {
    scene: &'a Scene,
    /// The scene's quads packed for 4-wide tests (the same answers as one by one, bit for bit).
    lanes: Option<&'a [QuadLanes]>,
    settings: &'a Settings,
    has_env: bool,
    env_nee: bool,
}

/// One camera path in flight: its whole state kept in one value rather than in a loop's locals,
/// so that paths can take turns segment by segment and the CPU overlaps their (independent) dependency chains.
struct Path {
    o: Vec3A,
    d: Vec3A,
    rng: Sampler,
    radiance: Vec3A,
    beta: Vec3A,
    segments: u32,
    /// The last scattering was a delta (or the camera): emission found by it cannot have been
    /// found by NEE, so it counts with full weight (this is what makes caustics).
    specular: bool,
    prev_p: Vec3A,
    prev_pdf: f32,
    done: bool,
    /// Rays cast by the path (counted only by `Tracer<true>`).
    rays: u32,
}

impl Path {
    /// A path leaving `o` along `d`, drawing from `rng`.
    #[inline(always)]
    fn new(o: Vec3A, d: Vec3A, rng: Sampler) -> Self {
        Self {
            o,
            d,
            rng,
            radiance: Vec3A::ZERO,
            beta: Vec3A::ONE,
            segments: 1,
            specular: true,
            prev_p: o,
            prev_pdf: 0.0,
            done: false,
            rays: 0,
        }
    }
}

impl<'a, const COUNT: bool> Tracer<'a, COUNT> {
    fn new(scene: &'a Scene, lanes: Option<&'a [QuadLanes]>, settings: &'a Settings) -> Self {
        let lights = &scene.lights;
        let has_env = lights.environment != Vec3A::ZERO;
        Self {
            scene,
            lanes,
            settings,
            has_env,
            env_nee: settings.nee && lights.environment_nee && has_env,
        }
    }

    /// Row `y` of the image into `row` (RGB per pixel): each pixel's samples traced
    /// `IN_FLIGHT` at a time, then four, the rest one by one. Returns the rays cast (0 unless `COUNT`).
    #[inline(always)]
    fn row(&self, y: u32, row: &mut [f32]) -> u64 {
        let spp = self.settings.spp.max(1);
        let mut rays = 0u64;
        for x in 0..self.scene.camera.width {
            let mut sum = Vec3A::ZERO;
            // A NaN or infinity from a degenerate configuration must never reach the image:
            // drop that sample (a zero-contribution sample, still counted). The samples are
            // added in order.
            let mut add = |(l, n): (Vec3A, u32)| {
                if l.is_finite() {
                    sum += l;
                }
                rays += u64::from(n);
            };
            let mut s = 0;
            while s + IN_FLIGHT <= spp {
                let paths = std::array::from_fn(|k| self.camera_path(x, y, s + k as u32));
                for l in self.trace_many::<{ IN_FLIGHT as usize }>(paths) {
                    add(l);
                }
                s += IN_FLIGHT;
            }
            if s + 4 <= spp {
                let paths = std::array::from_fn(|k| self.camera_path(x, y, s + k as u32));
                for l in self.trace_many::<4>(paths) {
                    add(l);
                }
                s += 4;
            }
            for s in s..spp {
                add(self.trace(self.camera_path(x, y, s)));
            }
            let v = sum / spp as f32;
            let i = 3 * x as usize;
            row[i] = v.x;
            row[i + 1] = v.y;
            row[i + 2] = v.z;
        }
        rays
    }

    /// Camera sample `s` of pixel (`x`, `y`): its stream and its jittered ray.
    #[inline(always)]
    fn camera_path(&self, x: u32, y: u32, s: u32) -> Path {
        let camera = &self.scene.camera;
        let mut rng = Sampler::new(self.settings.seed, y * camera.width + x, s);
        let (jx, jy) = rng.next_2d();
        Path::new(camera.origin(), camera.direction(x, y, jx, jy), rng)
    }

    /// Radiance of one camera sample (its path traced to the end) and the rays it cast.
    #[inline(always)]
    fn trace(&self, mut path: Path) -> (Vec3A, u32) {
        while !path.done {
            self.segment(&mut path);
        }
        (path.radiance, path.rays)
    }

    /// Radiance of `N` camera samples (a multiple of four), their paths advanced in turn, a
    /// segment each (each exactly as [`Tracer::trace`] would: the paths share nothing, so the
    /// bits are the same). Each turn their rays' spheres and quads are tested four paths at
    /// once ([`RayPack`]), the same answers as one by one; finished paths' lanes idle.
    #[inline(always)]
    fn trace_many<const N: usize>(&self, mut paths: [Path; N]) -> [(Vec3A, u32); N] {
        let geo = &self.scene.geometry;
        while paths.iter().any(|p| !p.done) {
            for four in paths.chunks_exact_mut(4) {
                if four.iter().all(|p| p.done) {
                    continue;
                }
                let o = std::array::from_fn(|k| four[k].o);
                let d = std::array::from_fn(|k| four[k].d);
                let shapes = RayPack::new(o, d).nearest_shape(geo);
                for (path, shape) in four.iter_mut().zip(shapes) {
                    if !path.done {
                        self.segment_after(path, shape);
                    }
                }
            }
        }
        paths.map(|p| (p.radiance, p.rays))
    }

    /// One segment of `path`: its closest hit, emission found there, and the scattering
    /// (with next-event estimation) or the end of the path (`path.done`).
    #[inline(always)]
    fn segment(&self, path: &mut Path) {
        let shape = (self.scene.geometry).nearest_shape(self.lanes, path.o, path.d, f32::INFINITY);
        self.segment_after(path, shape);
    }

    /// [`Tracer::segment`] given the closest sphere or quad on the path's ray, `shape`, as
    /// `Geometry::nearest_shape` finds it with an infinite range.
    #[inline(always)]
    fn segment_after(&self, path: &mut Path, shape: (f32, Option<Prim>)) {
        let (scene, s) = (self.scene, self.settings);
        let geo = &scene.geometry;
        if COUNT {
            path.rays += 1;
        }
        if path.segments >= s.max_depth {
            // Only an emitter or a miss can still add light: no closest hit needed.
            match geo.last_hit_after(shape, path.o, path.d) {
                LastHit::Miss => self.add_environment(path),
                LastHit::Emitter { t, quad } => {
                    let q = &geo.quads[quad as usize];
                    self.add_emission(path, path.o + t * path.d, q.emission, q.light);
                }
                LastHit::Dark => {}
            }
            path.done = true;
            return;
        }
        let Some((_, hit)) = geo.intersect_after(shape, path.o, path.d) else {
            self.add_environment(path);
            path.done = true;
            return;
        };

        if hit.emission != Vec3A::ZERO {
            self.add_emission(path, hit.p, hit.emission, hit.light);
        }

        let scattered = match scene.materials[hit.material as usize] {
            Material::Diffuse { albedo, texture } => {
                let albedo = match texture {
                    Some(t) => scene.textures[t as usize].sample(hit.uv),
                    None => albedo,
                };
                self.diffuse(path, &hit, albedo)
            }
            Material::Dielectric { ior } => {
                let (wi, scale, _) = scatter_dielectric(path.d, hit.n, ior, path.rng.next_f32());
                path.beta *= scale;
                let side = if wi.dot(hit.n) > 0.0 { hit.n } else { -hit.n };
                path.o = hit.p + offset(hit.p) * side;
                path.d = wi;
                path.specular = true;
                true
            }
        };
        if !scattered {
            path.done = true;
            return;
        }

        path.segments += 1;
        if path.segments > 3 {
            let q = path.beta.max_element().min(0.95);
            if path.rng.next_f32() >= q {
                path.done = true;
                return;
            }
            path.beta /= q;
        }
    }

    /// The environment seen by `path`'s ray (it left the scene), MIS-weighted when the
    /// environment is also sampled by NEE.
    #[inline(always)]
    fn add_environment(&self, path: &mut Path) {
        if self.has_env {
            let w = if path.specular || !self.env_nee {
                1.0
            } else {
                // Both strategies are cosine-distributed about the same normal.
                power_heuristic(path.prev_pdf, path.prev_pdf)
            };
            path.radiance += path.beta * self.scene.lights.environment * w;
        }
    }

    /// `emission` of area light `light` found by `path`'s ray at `p`, MIS-weighted against
    /// light sampling unless the last scattering was a delta (or NEE is off).
    #[inline(always)]
    fn add_emission(&self, path: &mut Path, p: Vec3A, emission: Vec3A, light: u32) {
        let (geo, lights) = (&self.scene.geometry, &self.scene.lights);
        let w = if path.specular || !self.settings.nee {
            1.0
        } else {
            let light_pdf = lights.areas.get(light as usize).map_or(0.0, |&q| {
                lights.area_pdf(&geo.quads[q as usize], path.prev_p, p, path.d)
            });
            power_heuristic(path.prev_pdf, light_pdf)
        };
        path.radiance += path.beta * emission * w;
    }

    /// Whether nothing lies on the shadow ray from `p` along `d` before `tmax` (a ray of
    /// `path`'s, counted when `COUNT`).
    #[inline(always)]
    fn visible(&self, path: &mut Path, p: Vec3A, d: Vec3A, tmax: f32) -> bool {
        if COUNT {
            path.rays += 1;
        }
        !self.scene.geometry.occluded_in(self.lanes, p, d, tmax)
    }

    /// Next-event estimation at a diffuse hit and the cosine-sampled continuation; false
    /// when the sampled direction is unusable (the path ends).
    #[inline(always)]
    fn diffuse(&self, path: &mut Path, hit: &Surface, albedo: Vec3A) -> bool {
        let n = if hit.n.dot(path.d) < 0.0 {
            hit.n
        } else {
            -hit.n
        };
        let p = hit.p + offset(hit.p) * n;
        if self.settings.nee {
            self.next_event(path, p, n, albedo);
        }
        let (u1, u2) = path.rng.next_2d();
        let wi = sample_cosine(n, u1, u2);
        let cos = n.dot(wi);
        if cos <= 0.0 {
            return false;
        }
        path.beta *= albedo;
        path.prev_pdf = cos * FRAC_1_PI;
        path.prev_p = p;
        path.specular = false;
        path.o = p;
        path.d = wi;
        true
    }

    /// Light sampled from the diffuse point `p` (normal `n` facing the incoming ray): every
    /// point light, one area light (MIS-weighted) and the environment when it is sampled.
    #[inline(always)]
    fn next_event(&self, path: &mut Path, p: Vec3A, n: Vec3A, albedo: Vec3A) {
        let geo = &self.scene.geometry;
        let lights = &self.scene.lights;
        let f = path.beta * albedo * FRAC_1_PI;
        for light in &lights.points {
            let to = light.position - p;
            let dist2 = to.length_squared();
            let dist = dist2.sqrt();
            let wi = to / dist;
            let cos = n.dot(wi);
            if cos > 0.0 && self.visible(path, p, wi, dist * (1.0 - 1e-4)) {
                path.radiance += f * light.intensity * (cos / dist2);
            }
        }
        if !lights.areas.is_empty() {
            let u_pick = path.rng.next_f32();
            let (u1, u2) = path.rng.next_2d();
            if let Some(ls) = lights.sample_area(&geo.quads, p, u_pick, u1, u2) {
                let cos = n.dot(ls.dir);
                if cos > 0.0 && self.visible(path, p, ls.dir, ls.dist * (1.0 - 1e-4)) {
                    let w = power_heuristic(ls.pdf, cos * FRAC_1_PI);
                    path.radiance += f * ls.radiance * (cos * w / ls.pdf);
                }
            }
        }
        if self.env_nee {
            let (u1, u2) = path.rng.next_2d();
            let wi = sample_cosine(n, u1, u2);
            if n.dot(wi) > 0.0 && self.visible(path, p, wi, f32::INFINITY) {
                // f * L * cos / pdf with pdf = cos / pi, times the MIS weight.
                let pdf = n.dot(wi) * FRAC_1_PI;
                path.radiance +=
                    path.beta * albedo * lights.environment * power_heuristic(pdf, pdf);
            }
        }
    }
}
