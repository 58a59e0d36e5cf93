//! Whether a checkpoint's parts fit together, and whether it fits the run asked for.

use std::path::Path;

use super::{show, Checkpoint, CheckpointError, Progress};
use crate::run::Settings;
use crate::tasks::Task;

impl Checkpoint {
    /// Checks that the parts fit: the settings are usable, the state continues, the history
    /// has one row per completed iteration, the points have one dimension.
    pub(super) fn check_consistent(&self) -> Result<(), String> {
        let s = &self.settings;
        // The run's settings are those asked for, but for what a time budget plans: fewer
        // pixels, spp or iterations.
        let r = &self.requested;
        let planned = Settings {
            scale: r.scale,
            spp: r.spp,
            iterations: r.iterations,
            eval_every: r.eval_every,
            ..s.clone()
        };
        let fits = if r.budget_seconds.is_some() {
            planned == *r && s.spp <= r.spp && s.iterations <= r.iterations
        } else {
            s == r
        };
        if !fits {
            return Err("the run's settings are not those asked for".into());
        }
        if s.iterations == 0 || s.samples == 0 || s.spp == 0 || s.eval_every == 0 {
            return Err("iterations, samples, spp and eval_every must be at least 1".into());
        }
        if s.samples > crate::run::MAX_SAMPLES {
            return Err(format!(
                "{} samples, at most {}",
                s.samples,
                crate::run::MAX_SAMPLES
            ));
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(s.sigma0) || !positive(s.lr) || !positive(s.fd_step) {
            return Err("sigma0, lr and fd_step must be finite and positive".into());
        }
        if s.scale
            .is_some_and(|v| !positive(v) || v > crate::run::MAX_SCALE)
            || s.fov_degrees.is_some_and(|v| !positive(v) || v >= 180.0)
            || s.budget_seconds.is_some_and(|v| !positive(v))
        {
            return Err("scale, fov_degrees or budget_seconds is out of range".into());
        }
        let non_negative = self.optimisation_seconds >= 0.0 && self.render_seconds >= 0.0;
        if self
            .history
            .last()
            .is_some_and(|r| r.renders != self.renders)
        {
            return Err("the renders are not the history's".into());
        }
        if !non_negative {
            return Err("the times must be non-negative".into());
        }
        let done = self.history.len();
        // The image method records a row per ask told: at most one a render.
        let rows = match self.progress {
            Progress::Image(_) => s.samples.saturating_mul(s.iterations),
            _ => s.iterations,
        };
        if done > rows {
            return Err(format!("{done} history rows, at most {rows}"));
        }
        if let Some((i, row)) = self
            .history
            .iter()
            .enumerate()
            .find(|(i, r)| r.iteration != *i)
        {
            return Err(format!("history row {i} is iteration {}", row.iteration));
        }
        let (dim, iteration) = match &self.progress {
            Progress::Loop(run) => (run.theta().len(), run.iteration()),
            Progress::Baseline(run) => (run.theta().len(), run.iteration()),
            Progress::Adaptive(search) => {
                self.check_search(search)?;
                (search.dim(), done)
            }
            Progress::Image(m) => {
                if m.evaluations() != self.renders {
                    return Err("the renders are not the least-squares run's".into());
                }
                (m.theta().len(), done)
            }
        };
        if iteration != done {
            return Err(format!(
                "the state is at iteration {iteration}, the history has {done} rows"
            ));
        }
        if self.best_point.len() != dim {
            return Err(format!(
                "a best point of dimension {}, theta has {dim}",
                self.best_point.len()
            ));
        }
        if let Some(p) = self.snapshots.iter().find(|p| p.len() != dim) {
            return Err(format!(
                "a snapshot of dimension {}, theta has {dim}",
                p.len()
            ));
        }
        let most = match self.progress {
            Progress::Adaptive(_) | Progress::Image(_) => done + 1,
            _ => 6,
        };
        if self.snapshots.len() > most {
            return Err(format!(
                "{} snapshots, at most {most}",
                self.snapshots.len()
            ));
        }
        if dim == 0 || self.snapshots.iter().flatten().any(|v| !v.is_finite()) {
            return Err("theta is empty or a snapshot is not finite".into());
        }
        Ok(())
    }

    /// Checks that the checkpoint is a run of `task` with the settings `requested` (those
    /// the command line asks for), naming the first setting that differs.
    ///
    /// # Errors
    /// [`CheckpointError::Mismatch`] (or `Inconsistent` if the point's dimension is not the
    /// task's).
    pub fn check_matches(
        &self,
        task: &Task,
        requested: &Settings,
        path: &Path,
    ) -> Result<(), CheckpointError> {
        let mismatch = |setting: &str, found: String, here: String| CheckpointError::Mismatch {
            path: path.into(),
            setting: setting.into(),
            found,
            here,
        };
        if self.task != task.name() {
            return Err(mismatch("task", self.task.clone(), task.name().into()));
        }
        let (Ok(serde_json::Value::Object(found)), Ok(serde_json::Value::Object(here))) = (
            serde_json::to_value(&self.requested),
            serde_json::to_value(requested),
        ) else {
            return Err(CheckpointError::Inconsistent {
                path: path.into(),
                reason: "the settings do not serialise".into(),
            });
        };
        for (key, value) in &here {
            let old = found.get(key).cloned().unwrap_or(serde_json::Value::Null);
            if &old != value {
                return Err(mismatch(key, show(&old), show(value)));
            }
        }
        let dim = self.best_point.len();
        if dim != task.dim() {
            return Err(CheckpointError::Inconsistent {
                path: path.into(),
                reason: format!(
                    "theta has {dim} parameters, {} has {}",
                    task.name(),
                    task.dim()
                ),
            });
        }
        Ok(())
    }

    /// Checks the searches' record against their run: every value told, the best.
    fn check_search(&self, search: &plateau_free::AskTell) -> Result<(), String> {
        let s = &self.settings;
        let (values, budget) = (&self.values, s.samples.saturating_mul(s.iterations));
        if values.len() > budget || search.evaluations() != values.len() {
            return Err(format!(
                "{} values for {} evaluations of a budget of {budget}",
                values.len(),
                search.evaluations()
            ));
        }
        if values.is_empty() && !self.history.is_empty() {
            return Err("history without evaluations".into());
        }
        if self.best_value.is_some_and(|v| !v.is_finite()) {
            return Err("the best value is not finite".into());
        }
        if self.renders != values.len() {
            return Err("the renders are not the values told".into());
        }
        Ok(())
    }
}
