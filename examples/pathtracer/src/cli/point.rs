//! The task and the parameters a command works at (`render`, `export`): the target by
//! default, the start with `--initial`, or the values of `--params` or `--params-file`.

use std::path::{Path, PathBuf};

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
    #[arg(long, conflicts_with_all = ["target", "params", "params_file"])]
    initial: bool,
    /// At the target parameters (the default).
    #[arg(long, conflicts_with_all = ["params", "params_file"])]
    target: bool,
    /// At these parameters, comma-separated (as many as the task has) [default: the target's,
    /// or with --initial the start's].
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, value_parser = values::finite)]
    params: Option<Vec<f64>>,
    /// At the parameters in this file: a JSON array of finite numbers (as many as the task
    /// has), for tasks too large for a command line (TEXTURE's 49,152); the `theta.json` an
    /// export writes is one.
    #[arg(long, conflicts_with = "params")]
    params_file: Option<PathBuf>,
}

impl Point {
    /// The task, the parameters and which they are (`"target"`, `"start"` or `"given"`); a
    /// `--params` or `--params-file` of another length than the task's, or a file that is
    /// not a JSON array of finite numbers, is a usage error naming the option.
    pub(super) fn resolve(&self) -> Result<(Task, Vec<f64>, &'static str)> {
        let task = find_task(&self.task)?;
        let (theta, which, option) = match (&self.params, &self.params_file) {
            (Some(p), _) => (p.clone(), "given", "--params".to_string()),
            (None, Some(path)) => (
                read_params(path)?,
                "given",
                format!("--params-file {}", path.display()),
            ),
            (None, None) if self.initial => (task.start(), "start", String::new()),
            (None, None) => (task.target(), "target", String::new()),
        };
        if theta.len() != task.dim() {
            return Err(usage(format!(
                "{option}: {} values; allowed: {} ({}'s parameter count)",
                theta.len(),
                task.dim(),
                task.name()
            )));
        }
        Ok((task, theta, which))
    }
}

/// The parameters of a `--params-file`: a JSON array of finite numbers.
fn read_params(path: &Path) -> Result<Vec<f64>> {
    let name = path.display();
    let text = std::fs::read_to_string(path)
        .map_err(|e| usage(format!("--params-file {name}: cannot be read ({e})")))?;
    let theta: Vec<f64> = serde_json::from_str(&text).map_err(|e| {
        usage(format!(
            "--params-file {name}: not a JSON array of numbers ({e})"
        ))
    })?;
    if let Some(k) = theta.iter().position(|t| !t.is_finite()) {
        return Err(usage(format!(
            "--params-file {name}: value {k} is {}; allowed: finite numbers",
            theta[k]
        )));
    }
    Ok(theta)
}
