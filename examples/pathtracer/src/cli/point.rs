//! The task and the parameters a command works at (`render`, `export`): the target by
//! default, the start with `--initial`, or the values of `--params`.

use super::{find_task, usage, values};
use crate::report::Result;
use crate::tasks::Task;

/// A task and where in its parameter space: flattened into a command's options.
#[derive(clap::Args)]
pub(super) struct Point {
    /// The task: cup, shadow, occlusion, gi, sort, caustic or texture.
    #[arg(value_parser = values::task)]
    task: String,
    /// At the start parameters.
    #[arg(long, conflicts_with_all = ["target", "params"])]
    initial: bool,
    /// At the target parameters (the default).
    #[arg(long, conflicts_with = "params")]
    target: bool,
    /// At these parameters, comma-separated (as many as the task has) [default: the target's,
    /// or with --initial the start's].
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, value_parser = values::finite)]
    params: Option<Vec<f64>>,
}

impl Point {
    /// The task, the parameters and which they are (`"target"`, `"start"` or `"given"`); a
    /// `--params` of another length than the task's is a usage error naming both counts.
    pub(super) fn resolve(&self) -> Result<(Task, Vec<f64>, &'static str)> {
        let task = find_task(&self.task)?;
        let (theta, which) = match &self.params {
            Some(p) => (p.clone(), "given"),
            None if self.initial => (task.start(), "start"),
            None => (task.target(), "target"),
        };
        if theta.len() != task.dim() {
            return Err(usage(format!(
                "--params: {} values; allowed: {} ({}'s parameter count)",
                theta.len(),
                task.dim(),
                task.name()
            )));
        }
        Ok((task, theta, which))
    }
}
