//! What a run can be told: the gradient method, the sampler, the renderer seeds, the task's
//! hyperparameters and their overrides, and how often the image error is measured.

use plateau_free::Sampling;
use serde::{Deserialize, Serialize};

use crate::tasks::{Task, View};

/// The largest resolution multiplier (`--scale`): 64 times the task's width and height.
/// Beyond, an image's pixels no longer fit in memory (and a scale of 1e300, in an `usize`).
pub const MAX_SCALE: f64 = 64.0;

/// The most evaluations per gradient (`--samples`). Each is a render; the estimator keeps
/// N points of the task's dimension, so a count near `usize::MAX` cannot even be allocated.
pub const MAX_SAMPLES: usize = 1 << 16;

/// `--method polished`: the share of the evaluations that the adaptive search gets after the
/// paper's loop, unless `--polish` gives another (one value for every task:
/// `docs/convergence.md`, table 8, and "Renders to the paper's answer").
pub const POLISH: f64 = 0.5;

/// The share that polished runs written before [`POLISH`] became 0.5 ran with: their
/// checkpoints and summaries either say 0.25 or, older still, nothing.
pub const POLISH_BEFORE: f64 = 0.25;

/// Points on a run's image-error curve at the defaults (`--eval-every` overrides it).
pub const CURVE_POINTS: usize = 100;

/// Every how many iterations a run of `iterations` renders its current parameters for the
/// image-error curve, so that the curve has about `points` points (at most one an iteration).
/// Those renders cost time the optimisation does not need, hence not every iteration.
pub fn eval_every(iterations: usize, points: usize) -> usize {
    (iterations / points).max(1)
}

/// How the gradient is obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The plateau-free gradient (the paper's method).
    Plateau,
    /// Small-step central finite differences: what a gradient sees without smoothing.
    Fd,
    /// Simultaneous-perturbation stochastic approximation.
    Spsa,
    /// The library's adaptive search (`plateau_free::Minimizer`): mirrored Gaussian pairs with
    /// step-size and covariance adaptation, a plateau rule and restarts from the start,
    /// given the same evaluations (N x iterations), sigma0, bounds and seed as the paper loop.
    Adaptive,
    /// The paper's loop (plateau-free gradient, Adam, annealing) on the first half of the
    /// evaluations ([`POLISH`]; `--polish` sets the last share), then the adaptive search from
    /// its best point at its last spread (`plateau_free::Minimizer::polish(0.5)` with
    /// `Strategy::Paper`).
    Polished,
    /// The image, not one number: damped Gauss-Newton on the residual image (rendered minus
    /// reference, per pixel and channel) with the Gaussian-smoothed Jacobian estimated on the
    /// task's footprint (`plateau_free::LeastSquares`): N / 2 antithetic pairs per Jacobian,
    /// sigma0 annealed over the N x iterations renders, the task's box and the run's seed.
    Image,
}

/// Which renderer seed each evaluation uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Crn {
    /// Every render, the reference included, uses the run's seed: the loss is a
    /// deterministic function of theta and reaches zero at the target (the paper's code).
    Fixed,
    /// Each antithetic pair shares a fresh seed from the estimator; the reference keeps the
    /// run's seed (the loss keeps a noise floor).
    Pair,
}

/// Everything a run can be told.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// How the gradient is obtained.
    pub method: Method,
    /// How perturbations are drawn.
    pub sampling: Sampling,
    /// Whether every perturbation is paired with its negative.
    pub antithetic: bool,
    /// Whether sigma follows the paper's annealing schedule (else it stays sigma0).
    pub anneal: bool,
    /// N: evaluations of the objective per gradient estimate.
    pub samples: usize,
    /// Initial smoothing spread, in parameter units.
    pub sigma0: f64,
    /// Adam's learning rate.
    pub lr: f64,
    /// Samples per pixel of every render.
    pub spp: u32,
    /// Optimisation steps.
    pub iterations: usize,
    /// Seed of the renderer's noise and of the estimator's draws.
    pub seed: u64,
    /// Which renderer seed each evaluation uses.
    pub crn: Crn,
    /// Finite-difference step, in parameter units.
    pub fd_step: f64,
    /// Horizontal field of view replacing the task's, degrees.
    pub fov_degrees: Option<f64>,
    /// Resolution multiplier.
    pub scale: Option<f64>,
    /// Render the current parameters for the image-error curve every this many iterations.
    pub eval_every: usize,
    /// Stop when the optimisation (renders for the gradient included) has used this much time.
    pub budget_seconds: Option<f64>,
    /// The stop rule (`plateau_free::run::Stall`): end the run when the best value has not
    /// improved over this fraction of the N x iterations evaluations (`None`: the budget
    /// alone ends it). Runs written before the rule read as `None`.
    #[serde(default)]
    pub stall: Option<f64>,
    /// With [`Method::Polished`], the share of the evaluations, in `[0, 1)`, that the adaptive
    /// search gets after the paper's loop. Runs written before the option read as
    /// [`POLISH_BEFORE`], the share they ran with.
    #[serde(default = "default_polish")]
    pub polish: f64,
}

/// What a run written before `polish` was a setting ran with.
fn default_polish() -> f64 {
    POLISH_BEFORE
}

impl Settings {
    /// The task's paper defaults (supplemental Table 1) with the plateau-free gradient.
    pub fn defaults(task: &Task) -> Self {
        let d = task.defaults();
        Settings {
            method: Method::Plateau,
            sampling: Sampling::Radial,
            antithetic: true,
            anneal: true,
            samples: d.samples,
            sigma0: d.sigma0,
            lr: d.lr,
            spp: d.spp,
            iterations: d.iterations,
            seed: 0,
            crn: Crn::Fixed,
            fd_step: 1e-3,
            fov_degrees: None,
            scale: None,
            eval_every: eval_every(d.iterations, CURVE_POINTS),
            budget_seconds: None,
            stall: None,
            polish: POLISH,
        }
    }

    /// Whether iteration `iteration` renders the current parameters for the image-error
    /// curve: every `eval_every`-th from the first, and the last.
    pub fn records_image_error(&self, iteration: usize) -> bool {
        iteration % self.eval_every == 0 || iteration + 1 == self.iterations
    }

    /// The view overrides (field of view, resolution) every render of the run uses.
    pub fn view(&self) -> View {
        View {
            fov_degrees: self.fov_degrees,
            scale: self.scale,
        }
    }
}

impl Method {
    /// What `optimize` and `all` run without `--method`: the paper's loop polished by the
    /// adaptive search, which reached the paper's parameter MSE on more seeds of SHADOW and CUP
    /// than the loop alone (`docs/convergence.md`, table 8). With `--budget` (a time budget,
    /// which only the paper's loop supports) it is [`Method::Plateau`]. The reproduction pages
    /// (Table 2, the ablation, Fig. 1-4) build their runs from [`Settings::defaults`], the
    /// paper's loop.
    pub const TASK_DEFAULT: Method = Method::Polished;

    /// Whether the method draws antithetic pairs (and so needs an even N).
    pub fn pairs(self) -> bool {
        matches!(self, Method::Plateau | Method::Polished | Method::Image)
    }

    /// The spelling of `--method` for this method.
    pub fn as_arg(self) -> &'static str {
        match self {
            Method::Plateau => "plateau",
            Method::Fd => "fd",
            Method::Spsa => "spsa",
            Method::Adaptive => "adaptive",
            Method::Polished => "polished",
            Method::Image => "image",
        }
    }
}

impl Method {
    /// A short label for tables and legends: `paper_loop` names a paper-loop run (its
    /// sampler and switches, worded by the caller), `polish` a polished run's share (`None`: a
    /// run written before the share was a setting, which ran with [`POLISH_BEFORE`]; the share
    /// is named only where it is not the default).
    pub fn label(self, paper_loop: impl FnOnce() -> String, polish: Option<f64>) -> String {
        match self {
            Method::Plateau => paper_loop(),
            Method::Fd => "finite difference".into(),
            Method::Spsa => "SPSA".into(),
            Method::Adaptive => "adaptive search".into(),
            Method::Polished => match polish.unwrap_or(POLISH_BEFORE) {
                share if share != POLISH => format!("paper loop, polished (polish {share})"),
                _ => "paper loop, polished".into(),
            },
            Method::Image => "image (Gauss-Newton)".into(),
        }
    }
}

impl Settings {
    /// A short label for tables and legends.
    pub fn label(&self) -> String {
        let paper_loop = || {
            let mut s = format!("{:?}", self.sampling).to_lowercase();
            if !self.antithetic {
                s.push_str(", no antithetic");
            }
            if !self.anneal {
                s.push_str(", no annealing");
            }
            s
        };
        self.method.label(paper_loop, Some(self.polish))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Settings written before `polish` was one (every committed run's checkpoint) read as
    /// the share they ran with; the label names a share only where it is not the default.
    #[test]
    fn settings_without_a_polish_read_as_the_share_they_ran_with() {
        let task = crate::tasks::all().into_iter().next().unwrap();
        let mut s = Settings::defaults(&task);
        s.polish = 0.75;
        let mut json = serde_json::to_value(&s).unwrap();
        json.as_object_mut().unwrap().remove("polish");
        let read: Settings = serde_json::from_value(json).unwrap();
        assert_eq!(read.polish, POLISH_BEFORE);
        assert_eq!(Settings::defaults(&task).polish, POLISH);
        let polished = |share| Method::Polished.label(String::new, share);
        assert_eq!(polished(None), "paper loop, polished (polish 0.25)");
        assert_eq!(polished(Some(POLISH)), "paper loop, polished");
        assert_eq!(polished(Some(0.25)), "paper loop, polished (polish 0.25)");
        assert_eq!(Method::Plateau.label(|| "radial".into(), None), "radial");
    }
}
