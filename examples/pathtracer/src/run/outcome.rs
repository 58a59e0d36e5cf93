//! What a run yields: its history (`history.csv`) and summary (`summary.json`).

use std::path::Path;

use serde::{Deserialize, Serialize};

use plateau_free::Sampling;

use super::interrupt::Interrupted;
use super::{Crn, Method};
use crate::report::{self, Result};

/// One row of `history.csv`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// The iteration, from 0.
    pub iteration: usize,
    /// The smoothing spread of the iteration.
    pub sigma: f64,
    /// Mean image MSE over the iteration's perturbed renders.
    pub loss: f64,
    /// Final parameter MSE.
    pub param_mse: f64,
    /// Image MSE of the current parameters (every `eval_every` iterations).
    pub image_mse: Option<f64>,
    /// Renders of the objective so far, this iteration's included: every evaluation of the
    /// loss is one render (the evaluation-only renders are not among them). Read as 0 from a
    /// checkpoint of a build that did not count ([`super::recount`] derives them).
    #[serde(default)]
    pub renders: usize,
    /// Evaluation-only renders so far: one per `image_mse` measured (never seen by the
    /// optimiser).
    #[serde(default)]
    pub eval_renders: usize,
    /// Optimisation time so far (renders for the gradient, estimator, Adam), seconds.
    pub seconds: f64,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    /// The task's name.
    pub task: String,
    /// How the gradient is obtained.
    pub method: Method,
    /// How perturbations are drawn.
    pub sampling: Sampling,
    /// Whether every perturbation is paired with its negative.
    pub antithetic: bool,
    /// Whether sigma follows the paper's annealing schedule (else it stays sigma0).
    pub anneal: bool,
    /// Which renderer seed each evaluation uses.
    pub crn: Crn,
    /// Optimisation steps.
    pub iterations: usize,
    /// N: evaluations of the objective per gradient estimate.
    pub samples: usize,
    /// Samples per pixel of every render.
    pub spp: u32,
    /// Initial smoothing spread, in parameter units.
    pub sigma0: f64,
    /// Adam's learning rate.
    pub lr: f64,
    /// Seed of the renderer's noise and of the estimator's draws.
    pub seed: u64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Number of parameters.
    pub dim: usize,
    /// Evaluations of the objective in all.
    pub evaluations: usize,
    /// Renders of the objective in all (one per evaluation, the replayed ones of a resumed
    /// run included): the last row's `renders`.
    #[serde(default)]
    pub renders: usize,
    /// The renders of the objective at which the parameter MSE first reached the paper's
    /// (main paper Table 2); `None` if it never did or the paper has no number for the task.
    #[serde(default)]
    pub renders_to_paper: Option<usize>,
    /// Evaluation-only renders, never seen by the optimiser: the image MSE of the history's
    /// rows, the initial and the final image, the final image at another seed, and the
    /// progress strip's frames.
    #[serde(default)]
    pub evaluation_renders: usize,
    /// Renders of the target: the reference, and the reference at another seed.
    #[serde(default)]
    pub reference_renders: usize,
    /// Parameter MSE at the start.
    pub initial_param_mse: f64,
    /// Image MSE at the start.
    pub initial_image_mse: f64,
    /// Final parameter MSE.
    pub param_mse: f64,
    /// Final image against the reference, both rendered with the run's seed.
    pub image_mse: f64,
    /// Final image against the reference, both rendered with a seed the run never used.
    pub image_mse_other_seed: f64,
    /// Optimisation time per iteration, seconds.
    pub seconds_per_iteration: f64,
    /// Of which rendering.
    pub render_seconds_per_iteration: f64,
    /// Of which the estimator and Adam (everything but rendering).
    pub overhead_seconds_per_iteration: f64,
    /// Optimisation time in all, seconds.
    pub seconds_total: f64,
    /// Whether the time budget stopped the run.
    pub stopped_early: bool,
    /// Whether Ctrl-C stopped the run before its end (`--resume` continues it).
    #[serde(default)]
    pub interrupted: bool,
    /// A polished run's share of the renders for the polish (`--polish`); absent for the
    /// other methods and in polished runs written before the option (they ran with
    /// [`POLISH_BEFORE`](super::POLISH_BEFORE)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polish: Option<f64>,
    /// The final parameters (omitted above 16 dimensions).
    pub final_theta: Option<Vec<f64>>,
    /// The target parameters (omitted above 16 dimensions).
    pub target_theta: Option<Vec<f64>>,
}

/// The result of a run.
#[derive(Serialize, Deserialize)]
pub struct Outcome {
    /// `summary.json`.
    pub summary: Summary,
    /// `history.csv`: one row per iteration.
    pub history: Vec<Row>,
}

impl Outcome {
    /// The outcome of a run that ended, or [`Interrupted`] for one that was interrupted
    /// (after writing its checkpoint; the caller's caller knows the command to continue).
    pub fn unless_interrupted(self) -> Result<Outcome> {
        if self.summary.interrupted {
            return Err(Box::new(Interrupted {
                resume: String::new(),
            }));
        }
        Ok(self)
    }
}

/// The renders at which `rows` first reach a parameter MSE at or below `paper` (`None`: never,
/// or no paper number).
pub fn renders_to(rows: &[Row], paper: Option<f64>) -> Option<usize> {
    let paper = paper?;
    rows.iter()
        .find(|r| r.param_mse <= paper)
        .map(|r| r.renders)
}

/// `history.csv`: one row per iteration.
pub fn write_history(path: &Path, history: &[Row]) -> Result<()> {
    report::write_csv(
        path,
        &[
            "iteration",
            "sigma",
            "loss",
            "param_mse",
            "image_mse",
            "renders",
            "eval_renders",
            "seconds",
        ],
        history.iter().map(|r| {
            vec![
                r.iteration.to_string(),
                format!("{:e}", r.sigma),
                format!("{:e}", r.loss),
                format!("{:e}", r.param_mse),
                r.image_mse.map_or(String::new(), |v| format!("{v:e}")),
                r.renders.to_string(),
                r.eval_renders.to_string(),
                format!("{:.6}", r.seconds),
            ]
        }),
    )
}
