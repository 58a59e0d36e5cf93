//! The paper's task scenes: each maps a parameter vector theta to an image.
//!
//! The optimiser sees only [`Task::render`] (and the loss it computes from two images); a
//! task knows nothing of gradients.

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

/// View overrides used by experiments (Fig. 3 changes the field of view, the speed/accuracy study the resolution).
#[derive(Clone, Copy, Debug, Default)]
pub struct View {
    /// Horizontal field of view in degrees, replacing the task's.
    pub fov_degrees: Option<f64>,
    /// Resolution multiplier.
    pub scale: Option<f64>,
}

impl View {
    /// The task's pinhole camera with this view's overrides applied.
    pub fn camera(
        &self,
        position: Vec3,
        direction: Vec3,
        up: Vec3,
        hfov_degrees: f64,
        (width, height): (u32, u32),
    ) -> Camera {
        let scale = self
            .scale
            .filter(|s| s.is_finite() && *s > 0.0)
            .unwrap_or(1.0);
        let px = |n: u32| ((n as f64 * scale).round() as u32).max(1);
        Camera::new(
            position,
            direction,
            up,
            self.fov_degrees.unwrap_or(hfov_degrees),
            px(width),
            px(height),
        )
    }
}

/// One inverse-rendering task of the paper.
pub trait Task: Send + Sync {
    /// Short name: "cup", "shadow", "occlusion", "gi", "sort", "caustic", "texture".
    fn name(&self) -> &'static str;
    /// One sentence on what is optimised.
    fn description(&self) -> &'static str;
    /// Number of parameters.
    fn dim(&self) -> usize;
    /// Supplemental Table 1 hyperparameters (TEXTURE: ours, see docs/tasks.md).
    fn defaults(&self) -> Defaults;
    /// The paper's numbers; None for TEXTURE (no table entry).
    fn paper(&self) -> Option<Paper>;
    /// Where the optimisation starts.
    fn start(&self) -> Vec<f64>;
    /// The parameters of the reference image.
    fn target(&self) -> Vec<f64>;
    /// Box for the optimiser's projection, e.g. [0,1]^n; None if unbounded.
    fn bounds(&self) -> Option<(Vec<f64>, Vec<f64>)>;
    /// Longest path, in segments (2 = direct light only).
    fn max_depth(&self) -> u32;
    /// The scene at parameters `theta` (static parts are shared, built once in the constructor).
    fn scene(&self, theta: &[f64], view: View) -> Scene;
    /// Render the scene at parameters theta: must be cheap to call thousands of times (static geometry and its BVH built once, in the task's constructor, and shared).
    fn render(&self, theta: &[f64], seed: u64, spp: u32, view: View) -> Image {
        render(
            &self.scene(theta, view),
            &Settings::new(spp, seed, self.max_depth()),
        )
    }
}

/// Every task, in the paper's order (TEXTURE last).
pub fn all() -> Vec<Box<dyn Task>> {
    vec![
        Box::new(cup::Cup::new()),
        Box::new(shadow::Shadow::new()),
        Box::new(occlusion::Occlusion::new()),
        Box::new(gi::Gi::new()),
        Box::new(sort::Sort::new()),
        Box::new(caustic::Caustic::new()),
        Box::new(texture::TextureTask::new()),
    ]
}

/// The task called `name` (case-insensitive).
pub fn by_name(name: &str) -> Option<Box<dyn Task>> {
    let name = name.to_ascii_lowercase();
    let task: Box<dyn Task> = match name.as_str() {
        "cup" => Box::new(cup::Cup::new()),
        "shadow" => Box::new(shadow::Shadow::new()),
        "occlusion" => Box::new(occlusion::Occlusion::new()),
        "gi" => Box::new(gi::Gi::new()),
        "sort" => Box::new(sort::Sort::new()),
        "caustic" => Box::new(caustic::Caustic::new()),
        "texture" => Box::new(texture::TextureTask::new()),
        _ => return None,
    };
    Some(task)
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

/// The unit box [0, 1]^n.
pub(crate) fn unit_box(n: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    Some((vec![0.0; n], vec![1.0; n]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn param_mse_is_plain_mean() {
        assert!((param_mse(&[1.0, 2.0], &[0.0, 0.0]) - 2.5).abs() < 1e-15);
        assert_eq!(param_mse(&[1.0], &[]), f64::INFINITY);
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
                }
            }
        }
        assert!(by_name("nope").is_none());
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
