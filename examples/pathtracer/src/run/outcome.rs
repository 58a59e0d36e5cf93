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
    /// checkpoint of a build that did not count.
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

/// The renders of the objective at the end of each of the `rows` iterations of a finished
/// paper's loop that made `evaluations` in `iterations` iterations (as its summary says): the
/// same number every iteration.
///
/// # Errors
/// Rows that are not one per iteration, no iteration, or evaluations that do not divide evenly.
pub fn loop_renders(
    rows: usize,
    evaluations: usize,
    iterations: usize,
) -> std::result::Result<Vec<usize>, String> {
    if iterations == 0 || rows != iterations || evaluations % iterations != 0 {
        return Err(format!(
            "{evaluations} evaluations in {iterations} iterations, {rows} rows of history"
        ));
    }
    let per = evaluations / iterations;
    Ok((1..=rows).map(|i| i * per).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::{checkpoint, optimize_with, Control, Every, Method, Settings};
    use crate::tasks;

    /// A history of parameter errors 1, 0.5, 0.1, 0.2 after 2, 4, 6 and 8 renders.
    fn rows() -> Vec<Row> {
        [(1.0, 2), (0.5, 4), (0.1, 6), (0.2, 8)]
            .into_iter()
            .enumerate()
            .map(|(i, (param_mse, renders))| Row {
                iteration: i,
                sigma: 0.1,
                loss: 0.0,
                param_mse,
                image_mse: None,
                renders,
                eval_renders: 0,
                seconds: 0.0,
            })
            .collect()
    }

    #[test]
    fn renders_to_the_paper_are_those_of_the_first_row_at_or_below_it() {
        let rows = rows();
        assert_eq!(renders_to(&rows, Some(0.3)), Some(6));
        assert_eq!(renders_to(&rows, Some(0.1)), Some(6), "at counts");
        assert_eq!(renders_to(&rows, Some(2.0)), Some(2));
        assert_eq!(renders_to(&rows, Some(0.05)), None, "never reached");
        assert_eq!(renders_to(&rows, None), None, "no paper number");
        assert_eq!(renders_to(&[], Some(1.0)), None);
        assert_eq!(renders_to(&rows, Some(f64::NAN)), None);
    }

    #[test]
    fn the_paper_loops_renders_are_whole_per_iteration_or_refused() {
        assert_eq!(loop_renders(3, 12, 3), Ok(vec![4, 8, 12]));
        assert_eq!(loop_renders(1, 2, 1), Ok(vec![2]));
        assert!(loop_renders(3, 13, 3).is_err(), "not whole");
        assert!(loop_renders(2, 12, 3).is_err(), "a row missing");
        assert!(loop_renders(0, 0, 0).is_err(), "no iteration");
    }

    /// objective (the paper's loop N per iteration, finite differences 2n, the searches their
    /// batches, ending at the library's own count of evaluations), `eval_renders` every image
    /// error measured; the summary adds the initial, final and other-seed images and the strip,
    /// and the two references; `renders_to_paper` is that of the history (never, here: SHADOW's
    /// 1.81e-3 is out of reach in so few renders, written as null); and the paper loop's
    /// counts derived from its summary ([`loop_renders`]) equal the counted ones.
    #[test]
    fn renders_are_counted_and_derived_alike_from_the_summary() {
        let task = tasks::by_name("shadow").expect("the SHADOW task exists");
        for (method, iterations) in [
            (Method::Plateau, 10),
            (Method::Fd, 6),
            (Method::Adaptive, 30),
            (Method::Polished, 20),
        ] {
            let mut s = Settings::defaults(&task);
            s.method = method;
            s.scale = Some(0.125);
            s.spp = 2;
            s.iterations = iterations;
            s.eval_every = 3;
            let dir = std::env::temp_dir()
                .join(format!("plateau-renders-{method:?}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            let ctl = Control {
                out: Some(&dir),
                checkpoint: Some(dir.join(checkpoint::FILE)),
                every: Every::End,
                ..Control::default()
            };
            let o = optimize_with(&task, &s, ctl).expect("the run succeeds");
            let (h, m) = (&o.history, &o.summary);
            let last = h.last().expect("rows");
            assert_eq!(last.renders, m.evaluations, "{method:?}: all evaluations");
            assert_eq!(m.renders, m.evaluations, "{method:?}");
            match method {
                Method::Plateau | Method::Fd => {
                    let per = if method == Method::Fd {
                        2 * task.dim()
                    } else {
                        s.samples
                    };
                    for (i, r) in h.iter().enumerate() {
                        assert_eq!(r.renders, per * (i + 1), "{method:?} row {i}");
                    }
                }
                _ => assert!(
                    h.windows(2).all(|w| w[1].renders > w[0].renders) && h[0].renders >= 2,
                    "{method:?}: every row is a batch after the start"
                ),
            }
            let mut measured = 0;
            for r in h {
                measured += usize::from(r.image_mse.is_some());
                assert_eq!(r.eval_renders, measured, "{method:?}");
            }
            assert_eq!(m.evaluation_renders, measured + 3 + 6, "{method:?}");
            assert_eq!(m.reference_renders, 2);
            assert_eq!(m.renders_to_paper, None, "{method:?}");
            assert_eq!(
                m.renders_to_paper,
                renders_to(h, task.paper().map(|p| p.param_mse))
            );
            let json = std::fs::read_to_string(dir.join("summary.json")).unwrap();
            assert!(json.contains("\"renders_to_paper\": null"), "{json}");
            let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
            assert!(csv.starts_with(
                "iteration,sigma,loss,param_mse,image_mse,renders,eval_renders,seconds\n"
            ));

            if matches!(method, Method::Plateau | Method::Fd) {
                let from_summary = loop_renders(h.len(), m.evaluations, m.iterations).unwrap();
                let counted: Vec<usize> = h.iter().map(|r| r.renders).collect();
                assert_eq!(from_summary, counted, "{method:?}: from the summary");
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
}
