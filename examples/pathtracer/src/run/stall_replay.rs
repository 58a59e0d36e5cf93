//! The stop rule (`plateau_free::run::Stall`, `--stop-when-stalled`) replayed offline on a
//! finished full-length run, without rendering: where the run would have stopped, and its
//! parameter error there against at its end.
//!
//! The rule sees what the library sees: each iteration's batch of values (from the
//! checkpoint's log of every value, cut into the history's batches by its `renders` column)
//! and the smallest
//! of them, fed to the library's own [`Stall`] as [`plateau_free::Minimizer`] feeds it: the
//! adaptive search from its first generation, the polish from the hand-over (the paper's loop
//! is not judged: its schedule spans its share of the budget). So a run made with the rule
//! stops at the very iteration the replay names (`tests` below checks it against a run).

use std::path::Path;

use plateau_free::run::Stall;

use super::{adaptive, Checkpoint, Method, Progress, Row};
use crate::report::Result;

/// A full-length run and where the rule would have stopped it.
#[derive(Clone, Debug)]
pub struct Replayed {
    /// The task's name.
    pub task: String,
    /// The run's method.
    pub method: Method,
    /// The run's seed.
    pub seed: u64,
    /// N x iterations: the budget of renders of the objective.
    pub budget: usize,
    /// Renders of the objective at the run's end.
    pub renders_end: usize,
    /// Parameter MSE at the run's end.
    pub param_end: f64,
    /// The iteration (row) at which the rule stops, if it does.
    pub stop_row: Option<usize>,
    /// Renders of the objective at the stop (the end's when it does not stop).
    pub renders_stop: usize,
    /// Parameter MSE at the stop (the end's when it does not stop).
    pub param_stop: f64,
    /// Whether the rule judges this method at all (not the paper's loop alone).
    pub judged: bool,
}

/// Replays the rule with a window of `window` (a fraction of the budget) on the finished
/// run whose checkpoint is `path`.
///
/// # Errors
/// A checkpoint that cannot be read, of an unfinished run, or of a run that did not count
/// its renders (written before the runs counted: made again, it counts).
pub fn replay(path: &Path, window: f64) -> Result<Replayed> {
    let c = Checkpoint::load_any_build(path)?;
    if !c.finished {
        return Err(format!("{}: the run did not finish", path.display()).into());
    }
    if c.history.last().is_none_or(|r| r.renders == 0) {
        let why = "its history has no renders (written before the runs counted; run it again)";
        return Err(format!("{}: {why}", path.display()).into());
    }
    let rows = c.history.clone();
    let s = &c.settings;
    let budget = s.samples.saturating_mul(s.iterations);
    let last = rows.last().ok_or("a run without iterations")?;
    let mut out = Replayed {
        task: c.task.clone(),
        method: s.method,
        seed: s.seed,
        budget,
        renders_end: last.renders,
        param_end: last.param_mse,
        stop_row: None,
        renders_stop: last.renders,
        param_stop: last.param_mse,
        judged: false,
    };
    let Progress::Adaptive(_) = &c.progress else {
        return Ok(out); // The paper's loop: not judged within its schedule.
    };
    let values = &c.values;
    let first = match s.method {
        Method::Adaptive => 0,
        Method::Polished => adaptive::polish_starts_at(budget, s.samples, s.polish),
        _ => return Ok(out),
    };
    out.judged = true;
    if let Some(row) = stop_row(&rows, values, first, window, budget)? {
        out.stop_row = Some(row);
        out.renders_stop = rows[row].renders;
        out.param_stop = rows[row].param_mse;
    }
    Ok(out)
}

/// The row at which the rule stops, judging rows `first..` of a search whose every value is
/// `values` (the start's first, alone, with no row of its own).
fn stop_row(
    rows: &[Row],
    values: &[f64],
    first: usize,
    window: f64,
    budget: usize,
) -> Result<Option<usize>> {
    let mut rule = Stall::of_budget(window, budget)?;
    let mut before = 1; // the start
    for (i, row) in rows.iter().enumerate() {
        let batch = values
            .get(before..row.renders)
            .ok_or("the checkpoint's values do not cover the history's renders")?;
        before = row.renders;
        if i < first {
            continue;
        }
        let smallest = batch.iter().copied().fold(f64::INFINITY, f64::min);
        // The batch that spends the budget ends the run before the rule is asked.
        if rule.observe(batch.len(), smallest) && row.renders < budget {
            return Ok(Some(i));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::{checkpoint, optimize_with, Control, Every, Settings};
    use crate::tasks;

    /// A row without its timing: what a run with the rule must reproduce of the full run.
    fn bits(r: &Row) -> (usize, u64, u64, u64, Option<u64>, usize) {
        (
            r.iteration,
            r.sigma.to_bits(),
            r.loss.to_bits(),
            r.param_mse.to_bits(),
            r.image_mse.map(f64::to_bits),
            r.renders,
        )
    }

    /// The replay on a full-length run names the iteration at which a run made with the
    /// rule stops, bit for bit: the same rows up to it, the same renders and result there
    /// (the polish judged from the hand-over, the adaptive search from its start).
    #[test]
    fn stop_rule_run_stops_where_the_replay_says() {
        for (method, window) in [(Method::Polished, 0.02), (Method::Adaptive, 0.05)] {
            stops_where_the_replay_says(method, window);
        }
    }

    fn stops_where_the_replay_says(method: Method, window: f64) {
        let task = tasks::by_name("cup").unwrap();
        let mut s = Settings::defaults(&task);
        s.method = method;
        s.iterations = 100;
        s.spp = 2;
        s.scale = Some(0.125);
        s.eval_every = 10;
        let root = std::env::temp_dir().join(format!(
            "plateau-stall-{}-{}",
            method.as_arg(),
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&root);
        let run = |s: &Settings, dir: &Path| {
            std::fs::create_dir_all(dir).unwrap();
            let control = Control {
                out: Some(dir),
                checkpoint: Some(dir.join(checkpoint::FILE)),
                every: Every::Auto,
                ..Control::default()
            };
            optimize_with(&task, s, control).unwrap()
        };
        let full = run(&s, &root.join("full"));
        let replayed = replay(&root.join("full").join(checkpoint::FILE), window).unwrap();
        let stop = replayed.stop_row.expect("the replay stops this run early");
        assert!(replayed.renders_stop < replayed.budget);

        let ruled = run(
            &Settings {
                stall: Some(window),
                ..s.clone()
            },
            &root.join("ruled"),
        );
        assert_eq!(ruled.history.len(), stop + 1, "{method:?}");
        for (a, b) in ruled.history.iter().zip(&full.history) {
            // The image error is measured at the last row of either run, so compare it
            // before the stop only.
            if a.iteration < stop {
                assert_eq!(bits(a), bits(b), "{method:?} row {}", a.iteration);
            }
        }
        let last = ruled.history.last().unwrap();
        assert_eq!(last.renders, replayed.renders_stop);
        assert_eq!(last.param_mse.to_bits(), replayed.param_stop.to_bits());
        assert_eq!(ruled.summary.renders, replayed.renders_stop);
        assert!(ruled.summary.stopped_early);
        let _ = std::fs::remove_dir_all(&root);
    }
}
