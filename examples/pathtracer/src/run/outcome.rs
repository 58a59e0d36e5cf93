//! What a run yields: its history (`history.csv`) and summary (`summary.json`).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{Crn, Method, SamplerArg};
use crate::report::{self, Result};

/// One row of `history.csv`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    pub iteration: usize,
    pub sigma: f64,
    /// Mean image MSE over the iteration's perturbed renders.
    pub loss: f64,
    pub param_mse: f64,
    /// Image MSE of the current parameters (every `eval_every` iterations).
    pub image_mse: Option<f64>,
    /// Optimisation time so far (renders for the gradient, estimator, Adam), seconds.
    pub seconds: f64,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    pub task: String,
    pub method: Method,
    pub sampling: SamplerArg,
    pub antithetic: bool,
    pub anneal: bool,
    pub crn: Crn,
    pub iterations: usize,
    pub samples: usize,
    pub spp: u32,
    pub sigma0: f64,
    pub lr: f64,
    pub seed: u64,
    pub width: u32,
    pub height: u32,
    pub dim: usize,
    pub evaluations: usize,
    pub initial_param_mse: f64,
    pub initial_image_mse: f64,
    pub param_mse: f64,
    /// Final image against the reference, both rendered with the run's seed.
    pub image_mse: f64,
    /// Final image against the reference, both rendered with a seed the run never used.
    pub image_mse_other_seed: f64,
    pub seconds_per_iteration: f64,
    /// Of which rendering.
    pub render_seconds_per_iteration: f64,
    /// Of which the estimator and Adam (everything but rendering).
    pub overhead_seconds_per_iteration: f64,
    pub seconds_total: f64,
    pub stopped_early: bool,
    /// The final parameters (omitted above 16 dimensions).
    pub final_theta: Option<Vec<f64>>,
    pub target_theta: Option<Vec<f64>>,
}

/// The result of a run.
#[derive(Serialize, Deserialize)]
pub struct Outcome {
    pub summary: Summary,
    pub history: Vec<Row>,
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
            "seconds",
        ],
        history.iter().map(|r| {
            vec![
                r.iteration.to_string(),
                format!("{:e}", r.sigma),
                format!("{:e}", r.loss),
                format!("{:e}", r.param_mse),
                r.image_mse.map_or(String::new(), |v| format!("{v:e}")),
                format!("{:.6}", r.seconds),
            ]
        }),
    )
}
