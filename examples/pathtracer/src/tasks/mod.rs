//! The paper's task scenes: each maps a parameter vector theta to an image.
//!
//! The optimiser sees only [`Task::render`] (and the loss it computes from two images); a
//! task knows nothing of gradients.
//!
//! A task is a file that builds its scene ([`Scenario`]: start, target, the scene at theta)
//! and a row of [`TASKS`] (its name, depth, bounds and supplemental Table 1 hyperparameters);
//! the paper's published numbers are in [`PAPER`]. To add a task: a file implementing
//! [`Scenario`] and a row in [`TASKS`].

mod caustic;
pub mod cup;
mod gi;
mod occlusion;
mod shadow;
mod sort;
mod texture;

use glam::Vec3;

pub use crate::render::Image;
use crate::render::{render, Camera, Scene, Settings};

/// Every task, in the paper's order (TEXTURE last), with what every task states:
/// its name, its scene, the longest path in segments (2 = direct light only), whether theta
/// lives in the unit box [0, 1]^n (else in world units, unbounded), and its hyperparameters
/// (supplemental Table 1; TEXTURE's are ours, see docs/tasks.md).
#[rustfmt::skip]
const TASKS: [Entry; 7] = [
    //         name         scenario                               camera             depth unit box    N   sigma0 spp LR     iterations
    ("cup",       || Box::new(cup::Cup::new()),          cup::CAMERA,       4, true,  Defaults::new(2,  0.25,  16, 0.01,  400)),
    ("shadow",    || Box::new(shadow::Shadow),           shadow::CAMERA,    6, false, Defaults::new(2,  0.5,   32, 0.02,  400)),
    ("occlusion", || Box::new(occlusion::Occlusion),     occlusion::CAMERA, 6, true,  Defaults::new(2,  0.8,   32, 0.02,  600)),
    ("gi",        || Box::new(gi::Gi),                   gi::CAMERA,        6, true,  Defaults::new(4,  0.125, 16, 0.05,  500)),
    ("sort",      || Box::new(sort::Sort),               sort::CAMERA,      2, true,  Defaults::new(16, 0.5,   32, 0.01,  4000)),
    ("caustic",   || Box::new(caustic::Caustic),         caustic::CAMERA,   8, true,  Defaults::new(4,  0.125, 32, 0.01,  500)),
    ("texture",   || Box::new(texture::TextureTask),     texture::CAMERA,   2, true,  Defaults::new(32, 0.1,   4,  0.003, 4000)),
];

/// The paper's results for its black-box estimator, by task: image MSE, parameter MSE, GPU
/// seconds per iteration, Mitsuba 3's image and parameter MSE (main paper Tables 2 and 3 of
/// SPEC), and supplemental Table 2's (image, parameter) MSE at sigma0 = 0.5. TEXTURE has no
/// table entry.
#[rustfmt::skip]
const PAPER: [(&str, Paper); 6] = [
    //    task         image    param    s/iter  Mitsuba image, param  sigma0 = 0.5
    ("cup",       Paper::new(4.92e-6, 4.18e-7, 0.10, 5.49e-3, 7.5e-2,  Some((1.8e-7, 3.0e-7)))),
    ("shadow",    Paper::new(1.74e-5, 1.81e-3, 0.04, 1.64e-3, 5.06,    None)),
    ("occlusion", Paper::new(2.34e-4, 3.29e-3, 0.09, 5.85e-2, 52.3,    Some((2.2e-3, 7.2e-3)))),
    ("gi",        Paper::new(5.07e-5, 8.71e-4, 0.15, 3.78e-2, 3.87e-1, Some((1.0e-4, 6.6e-2)))),
    ("sort",      Paper::new(3.81e-3, 4.19e-1, 2.23, 1.18e-2, 6.64,    None)),
    ("caustic",   Paper::new(1.89e-5, 9.76e-5, 0.08, 3.12e-1, 8.50,    Some((2.4e-3, 2.2e-4)))),
];

/// What a task's file provides: where the optimisation starts, the parameters of the
/// reference image, and the scene at any parameters.
pub trait Scenario: Send + Sync {
    /// Where the optimisation starts.
    fn start(&self) -> Vec<f64>;
    /// The parameters of the reference image.
    fn target(&self) -> Vec<f64>;
    /// The scene at parameters `theta` seen by `camera` (the task's [`Shot`] after the
    /// [`View`]'s overrides); static parts are shared, built once in the constructor.
    fn scene(&self, theta: &[f64], camera: Camera) -> Scene;
    /// Which parameters each value of the image (pixel and channel, in [`Image::data`]'s
    /// order) can depend on, derived from the scene seen by `camera`; `None`: any pixel on
    /// any parameter (the default).
    fn footprint(&self, _camera: Camera) -> Option<plateau_free::vector::Sparsity> {
        None
    }
    /// The parameters that are angles of period 1 (the scene at `theta[i] + 1` is the scene
    /// at `theta[i]`, as a quarter turn of a square box): in a unit-box task their box is
    /// [-1, 2] (so that a run can go on through the seam instead of stopping against it) and
    /// the parameter error reads them on the circle ([`Task::param_mse`]). None by default.
    fn periodic(&self) -> &'static [usize] {
        &[]
    }
}

/// A row of [`TASKS`]: name, scenario, camera, max depth, unit box, defaults.
type Entry = (
    &'static str,
    fn() -> Box<dyn Scenario>,
    Shot,
    u32,
    bool,
    Defaults,
);

/// Supplemental Table 1 hyperparameters of a task.
#[derive(Clone, Copy, Debug)]
pub struct Defaults {
    /// N: evaluations of the objective per gradient estimate.
    pub samples: usize,
    /// Initial smoothing spread, in parameter units.
    pub sigma0: f64,
    /// Samples per pixel of every render.
    pub spp: u32,
    /// Adam learning rate.
    pub lr: f64,
    /// Optimisation steps.
    pub iterations: usize,
}

impl Defaults {
    /// The row of Table 1: N, sigma0, spp, LR, iterations.
    const fn new(samples: usize, sigma0: f64, spp: u32, lr: f64, iterations: usize) -> Self {
        Defaults {
            samples,
            sigma0,
            spp,
            lr,
            iterations,
        }
    }
}

/// The paper's published numbers for its black-box estimator (main paper Table 2 / Table 3 of SPEC).
#[derive(Clone, Copy, Debug)]
pub struct Paper {
    /// Final image MSE.
    pub image_mse: f64,
    /// Final parameter MSE.
    pub param_mse: f64,
    /// GPU seconds per iteration.
    pub seconds_per_iteration: f64,
    /// Mitsuba 3's final image MSE.
    pub mitsuba_image_mse: f64,
    /// Mitsuba 3's final parameter MSE.
    pub mitsuba_param_mse: f64,
    /// Supplemental Table 2: (image, param) at sigma0 = 0.5.
    pub sigma05: Option<(f64, f64)>,
}

impl Paper {
    /// A row of [`PAPER`], in the order of the fields.
    const fn new(
        image_mse: f64,
        param_mse: f64,
        seconds_per_iteration: f64,
        mitsuba_image_mse: f64,
        mitsuba_param_mse: f64,
        sigma05: Option<(f64, f64)>,
    ) -> Self {
        Paper {
            image_mse,
            param_mse,
            seconds_per_iteration,
            mitsuba_image_mse,
            mitsuba_param_mse,
            sigma05,
        }
    }
}

/// View overrides used by experiments (Fig. 3 changes the field of view, the speed/accuracy study the resolution).
#[derive(Clone, Copy, Debug, Default)]
pub struct View {
    /// Horizontal field of view in degrees, replacing the task's.
    pub fov_degrees: Option<f64>,
    /// Resolution multiplier.
    pub scale: Option<f64>,
}

/// Where a camera looks: along a direction, or at a point.
#[derive(Clone, Copy, Debug)]
pub enum Aim {
    /// This direction.
    Along(Vec3),
    /// This point.
    At(Vec3),
}

/// A task's pinhole camera: position, aim, up, horizontal field of view (degrees) and
/// resolution (pixels); a [`View`] may replace the field of view and scale the resolution.
#[derive(Clone, Copy, Debug)]
pub struct Shot {
    eye: Vec3,
    aim: Aim,
    up: Vec3,
    hfov_degrees: f64,
    size: (u32, u32),
}

impl Shot {
    /// The camera at `eye` aimed by `aim`.
    pub const fn new(eye: Vec3, aim: Aim, up: Vec3, hfov_degrees: f64, size: (u32, u32)) -> Self {
        Shot {
            eye,
            aim,
            up,
            hfov_degrees,
            size,
        }
    }

    /// The camera with `view`'s overrides applied.
    pub fn camera(&self, view: View) -> Camera {
        let scale = view
            .scale
            .filter(|s| s.is_finite() && *s > 0.0)
            .unwrap_or(1.0);
        let px = |n: u32| ((n as f64 * scale).round() as u32).max(1);
        let direction = match self.aim {
            Aim::Along(direction) => direction,
            Aim::At(point) => point - self.eye,
        };
        Camera::new(
            self.eye,
            direction,
            self.up,
            view.fov_degrees.unwrap_or(self.hfov_degrees),
            px(self.size.0),
            px(self.size.1),
        )
    }
}

/// One inverse-rendering task of the paper: its row of [`TASKS`] and its scene.
pub struct Task {
    name: &'static str,
    scenario: Box<dyn Scenario>,
    camera: Shot,
    max_depth: u32,
    unit_box: bool,
    defaults: Defaults,
}

impl Task {
    fn new(&(name, scenario, camera, max_depth, unit_box, defaults): &Entry) -> Self {
        Task {
            name,
            scenario: scenario(),
            camera,
            max_depth,
            unit_box,
            defaults,
        }
    }

    /// Short name: "cup", "shadow", "occlusion", "gi", "sort", "caustic", "texture".
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Number of parameters.
    pub fn dim(&self) -> usize {
        self.start().len()
    }

    /// Supplemental Table 1 hyperparameters (TEXTURE: ours, see docs/tasks.md).
    pub fn defaults(&self) -> Defaults {
        self.defaults
    }

    /// The paper's numbers; None for TEXTURE (no table entry).
    pub fn paper(&self) -> Option<Paper> {
        PAPER
            .iter()
            .find(|(name, _)| *name == self.name())
            .map(|(_, paper)| *paper)
    }

    /// Where the optimisation starts.
    pub fn start(&self) -> Vec<f64> {
        self.scenario.start()
    }

    /// The parameters of the reference image.
    pub fn target(&self) -> Vec<f64> {
        self.scenario.target()
    }

    /// Box for the optimiser's projection, [0, 1]^n but [-1, 2] for a periodic parameter
    /// ([`Scenario::periodic`]: a period on either side, so the seam is no wall); None if
    /// unbounded.
    pub fn bounds(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        let n = self.dim();
        self.unit_box.then(|| {
            let (mut lower, mut upper) = (vec![0.0; n], vec![1.0; n]);
            for &i in self.periodic() {
                (lower[i], upper[i]) = (-1.0, 2.0);
            }
            (lower, upper)
        })
    }

    /// The parameters that are angles of period 1 ([`Scenario::periodic`]).
    pub fn periodic(&self) -> &'static [usize] {
        self.scenario.periodic()
    }

    /// `theta` with each periodic parameter outside [0, 1] brought into [0, 1) by whole
    /// periods (the same scene); a value inside [0, 1] is kept as it is, so that a run that
    /// never left the unit box reads exactly as before.
    pub fn canonical(&self, theta: &[f64]) -> Vec<f64> {
        let mut theta = theta.to_vec();
        for &i in self.periodic() {
            if let Some(v) = theta.get_mut(i).filter(|v| !(0.0..=1.0).contains(*v)) {
                *v = v.rem_euclid(1.0);
            }
        }
        theta
    }

    /// The reported parameter error of `theta`: [`param_mse`] of its [`Task::canonical`]
    /// form against the target.
    pub fn param_mse(&self, theta: &[f64]) -> f64 {
        self.param_mse_to(theta, &self.target())
    }

    /// [`Task::param_mse`] against `target`, the task's target made once by the caller: a
    /// run's recorder measures every iteration, and TEXTURE builds its 49,152 target texels
    /// procedurally. Without periodic parameters `theta` is not copied.
    pub fn param_mse_to(&self, theta: &[f64], target: &[f64]) -> f64 {
        if self.periodic().is_empty() {
            return param_mse(theta, target);
        }
        param_mse(&self.canonical(theta), target)
    }

    /// Longest path, in segments (2 = direct light only).
    pub fn max_depth(&self) -> u32 {
        self.max_depth
    }

    /// The scene at parameters `theta` (static parts are shared, built once).
    pub fn scene(&self, theta: &[f64], view: View) -> Scene {
        self.scenario.scene(theta, self.camera.camera(view))
    }

    /// Which parameters each value of the image (pixel and channel) can depend on, from the
    /// scene ([`Scenario::footprint`]); every pixel on every parameter when the task does
    /// not say.
    ///
    /// # Errors
    /// A pattern the library refuses (an empty image).
    pub fn footprint(
        &self,
        view: View,
    ) -> Result<plateau_free::vector::Sparsity, plateau_free::Error> {
        let camera = self.camera.camera(view);
        match self.scenario.footprint(camera) {
            Some(pattern) => Ok(pattern),
            None => plateau_free::vector::Sparsity::dense(
                3 * camera.width as usize * camera.height as usize,
                self.dim(),
            ),
        }
    }

    /// Render the scene at parameters theta: cheap to call thousands of times (static
    /// geometry and its BVH are built once, when the task is made, and shared).
    pub fn render(&self, theta: &[f64], seed: u64, spp: u32, view: View) -> Image {
        render(
            &self.scene(theta, view),
            &Settings::new(spp, seed, self.max_depth()),
        )
    }
}

/// Every task, in the paper's order (TEXTURE last).
pub fn all() -> Vec<Task> {
    TASKS.iter().map(Task::new).collect()
}

/// The names of the tasks, in the paper's order (without building any).
pub fn names() -> impl Iterator<Item = &'static str> {
    TASKS.iter().map(|e| e.0)
}

/// The task called `name` (case-insensitive).
pub fn by_name(name: &str) -> Option<Task> {
    let name = name.to_ascii_lowercase();
    TASKS.iter().find(|e| e.0 == name).map(Task::new)
}

/// Plain mean of squared differences (the reported parameter error).
pub fn param_mse(a: &[f64], b: &[f64]) -> f64 {
    if a.is_empty() || a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / a.len() as f64
}

/// theta[i] as f32, 0 when missing or not finite (a short or NaN vector still renders).
pub(crate) fn param(theta: &[f64], i: usize) -> f32 {
    theta
        .get(i)
        .copied()
        .filter(|v| v.is_finite())
        .unwrap_or(0.0) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn param_mse_is_plain_mean() {
        assert!((param_mse(&[1.0, 2.0], &[0.0, 0.0]) - 2.5).abs() < 1e-15);
        assert_eq!(param_mse(&[1.0], &[]), f64::INFINITY);
    }

    /// GI's box rotation is read on the circle: a whole period away is the target itself,
    /// in the scene and in the error; inside [0, 1] nothing changes.
    #[test]
    fn a_periodic_parameter_is_read_on_the_circle() {
        let gi = by_name("gi").expect("gi");
        assert_eq!(gi.periodic(), [5]);
        let target = gi.target();
        let mut turned = target.clone();
        turned[5] += 1.0;
        assert!(gi.param_mse(&turned) < 1e-30);
        turned[5] -= 2.0;
        assert!(gi.param_mse(&turned) < 1e-30);
        // At the seam's far side (1.0) the error is the plain one, as runs before saw it.
        let mut seam = target.clone();
        seam[5] = 1.0;
        assert!((gi.param_mse(&seam) - 0.49 / 6.0).abs() < 1e-15);
        // A whole period away renders the same picture (up to float rounding in the turn),
        // unlike the seam.
        let view = View {
            scale: Some(0.25),
            ..Default::default()
        };
        let render = |theta: &[f64]| gi.render(theta, 2, 2, view);
        let reference = render(&target);
        let (same, seam) = (
            reference.mse(&render(&turned)),
            reference.mse(&render(&seam)),
        );
        assert!(same < 1e-3 * seam, "{same} vs {seam}");
        // Other tasks have no periodic parameter and keep their plain error.
        let cup = by_name("cup").expect("cup");
        assert!(cup.periodic().is_empty());
        assert_eq!(
            cup.param_mse(&cup.start()),
            param_mse(&cup.start(), &cup.target())
        );
    }

    #[test]
    fn names_round_trip_and_shapes_agree() {
        for task in all() {
            let again = by_name(task.name()).expect("by_name");
            assert_eq!(again.name(), task.name());
            assert_eq!(task.start().len(), task.dim());
            assert_eq!(task.target().len(), task.dim());
            if let Some((lo, hi)) = task.bounds() {
                assert_eq!(lo.len(), task.dim());
                for (i, (s, t)) in task.start().iter().zip(task.target()).enumerate() {
                    assert!(lo[i] <= *s && *s <= hi[i] && lo[i] <= t && t <= hi[i]);
                    // A period each side of the unit interval, or the unit interval.
                    let periodic = task.periodic().contains(&i);
                    assert_eq!(
                        (lo[i], hi[i]),
                        if periodic { (-1.0, 2.0) } else { (0.0, 1.0) }
                    );
                }
            }
        }
        assert!(by_name("nope").is_none());
        // Every row of the paper's numbers names a task; only TEXTURE has none.
        for (name, _) in PAPER {
            assert!(by_name(name).is_some(), "{name}");
        }
        let without: Vec<_> = all()
            .into_iter()
            .filter(|t| t.paper().is_none())
            .map(|t| t.name())
            .collect();
        assert_eq!(without, ["texture"]);
    }

    /// Each task renders finite, non-black images at start and target, and they differ.
    #[test]
    fn start_and_target_render_and_differ() {
        let view = View {
            scale: Some(0.5),
            ..Default::default()
        };
        for task in all() {
            let spp = 4;
            let start = task.render(&task.start(), 1, spp, view);
            let target = task.render(&task.target(), 1, spp, view);
            for (which, img) in [("start", &start), ("target", &target)] {
                assert!(
                    img.data.iter().all(|v| v.is_finite() && *v >= 0.0),
                    "{} {which}",
                    task.name()
                );
                let mean = img.data.iter().map(|&v| v as f64).sum::<f64>() / img.data.len() as f64;
                assert!(mean > 0.01, "{} {which} is black: {mean}", task.name());
            }
            let mse = start.mse(&target);
            assert!(
                mse > 1e-5,
                "{}: start and target look alike ({mse})",
                task.name()
            );
        }
    }

    /// The plateau the paper is about: near the start of CUP, SHADOW and OCCLUSION a small
    /// move leaves the loss (image MSE to the target, same seed) nearly unchanged, while the
    /// loss itself is large. A finite-difference gradient sees (almost) nothing there.
    #[test]
    fn start_sits_on_a_loss_plateau() {
        let view = View {
            scale: Some(0.5),
            ..Default::default()
        };
        for (name, step) in [("cup", 0.02), ("shadow", 0.1), ("occlusion", 0.05)] {
            let task = by_name(name).expect("task");
            let reference = task.render(&task.target(), 3, 8, view);
            let loss = |theta: &[f64]| task.render(theta, 3, 8, view).mse(&reference);
            let start = task.start();
            let l0 = loss(&start);
            for i in 0..task.dim() {
                for sign in [-1.0, 1.0] {
                    let mut moved = start.clone();
                    moved[i] += sign * step;
                    let l = loss(&moved);
                    eprintln!(
                        "{name} dim {i} step {}: loss {l0:.3e} -> {l:.3e}",
                        sign * step
                    );
                    assert!(
                        (l - l0).abs() < 0.05 * l0,
                        "{name}: loss {l0} -> {l} for a {step} step in dim {i}"
                    );
                }
            }
        }
    }
}
