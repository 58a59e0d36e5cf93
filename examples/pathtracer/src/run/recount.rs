//! The render counts of a finished run whose `history.csv` has none (written before the runs
//! counted them), derived exactly from its `checkpoint.json`, without rendering.
//!
//! The paper's loop (plateau, fd, spsa) makes one gradient estimate per iteration, each of the
//! same number of evaluations (N, 2n or 2), so iteration `i` ends at `(i + 1)` times the
//! checkpoint's evaluations per iteration (refused if they do not divide evenly). The adaptive
//! search and the polished loop hand over batches whose sizes depend on the values, so the
//! search is replayed from the checkpoint's values (as `--resume` does, but by any build: the
//! replay's hash of the points asked for must equal the checkpoint's, which proves that this
//! build's search asked for the very points, in the very batches, of the run). The test
//! `recount_equals_the_counted_renders` checks both against the counts of runs that counted.

use std::cell::Cell;
use std::panic::{self, AssertUnwindSafe};
use std::path::Path;
use std::time::Duration;

use super::{adaptive, Checkpoint, Control, Progress, Row, Run, Saver};
use crate::render::Image;
use crate::report::Result;
use crate::tasks;

/// The history of the finished run whose checkpoint is `path`, with `renders` and
/// `eval_renders` derived.
///
/// # Errors
/// A checkpoint that cannot be read or is inconsistent, of an unfinished run, of an unknown
/// task, of a paper loop whose evaluations per iteration are not whole, or of a search that
/// this build does not replay to the same points.
pub fn recount(path: &Path) -> Result<Vec<Row>> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let c = Checkpoint::parse_any_build(&bytes, path)?;
    if !c.finished {
        return Err(format!("{}: the run did not finish", path.display()).into());
    }
    let task = tasks::by_name(&c.task)
        .ok_or_else(|| format!("{}: unknown task {}", path.display(), c.task))?;
    let mut rows = match &c.progress {
        Progress::Loop { state } => {
            let mut rows = c.history.clone();
            let renders = loop_renders(rows.len(), state.history.evaluations, state.iteration)
                .map_err(|e| format!("{}: {e}", path.display()))?;
            for (r, count) in rows.iter_mut().zip(renders) {
                r.renders = count;
            }
            rows
        }
        Progress::Adaptive { .. } => replay(&task, c)?,
    };
    let mut measured = 0;
    for r in &mut rows {
        measured += usize::from(r.image_mse.is_some());
        r.eval_renders = measured;
    }
    Ok(rows)
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

/// The marker with which the replay's loss leaves the search: asked for a value the
/// checkpoint does not hold.
struct BeyondTheCheckpoint;

/// Replays the adaptive search of the finished checkpoint `c` of `task`; its history with the
/// counts derived.
fn replay(task: &tasks::Task, c: Checkpoint) -> Result<Vec<Row>> {
    let s = c.settings.clone();
    let start = task.start();
    // Never rendered: the replay answers every evaluation from the checkpoint.
    let reference = Image::new(1, 1);
    let render_time = Cell::new(Duration::ZERO);
    let saver = Saver {
        path: None,
        task: task.name(),
        requested: &s,
        s: &s,
        render_time: &render_time,
    };
    let ctl = Control {
        resume: Some(c),
        ..Control::default()
    };
    let run = Run {
        task,
        s: &s,
        reference: &reference,
        start: &start,
        ctl: &ctl,
        saver: &saver,
    };
    let loss = |_: &[f64], _: u64| -> f64 { panic::resume_unwind(Box::new(BeyondTheCheckpoint)) };
    match panic::catch_unwind(AssertUnwindSafe(|| adaptive::run(&run, &loss))) {
        Ok(finished) => Ok(finished?.2),
        Err(payload) if payload.is::<BeyondTheCheckpoint>() => {
            Err("the replay asked for more evaluations than the run made (another search?)".into())
        }
        Err(payload) => panic::resume_unwind(payload),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::{checkpoint, optimize_with, renders_to, Every, Method, Settings};

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

    /// Every method on a small SHADOW: the `renders` column counts every evaluation of the
    /// objective (the paper's loop N per iteration, finite differences 2n, the searches their
    /// batches, ending at the library's own count of evaluations), `eval_renders` every image
    /// error measured; the summary adds the initial, final and other-seed images and the strip,
    /// and the two references; `renders_to_paper` is that of the history (never, here: SHADOW's
    /// 1.81e-3 is out of reach in so few renders, written as null); and the counts derived
    /// from the checkpoint ([`recount`], by replay for the searches) equal the counted ones.
    #[test]
    fn renders_are_counted_and_recount_equals_the_counted_renders() {
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
            let file = dir.join(checkpoint::FILE);
            let ctl = Control {
                out: Some(&dir),
                checkpoint: Some(file.clone()),
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

            let derived = recount(&file).expect("the checkpoint recounts");
            let counts = |rows: &[Row]| -> Vec<(usize, usize)> {
                rows.iter().map(|r| (r.renders, r.eval_renders)).collect()
            };
            assert_eq!(counts(&derived), counts(h), "{method:?}: recount");
            if matches!(method, Method::Plateau | Method::Fd) {
                let from_summary = loop_renders(h.len(), m.evaluations, m.iterations).unwrap();
                let counted: Vec<usize> = h.iter().map(|r| r.renders).collect();
                assert_eq!(from_summary, counted, "{method:?}: from the summary");
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
    }

    /// A checkpoint whose search asked for other points (here: its values shifted by one
    /// evaluation) is refused, not miscounted.
    #[test]
    fn a_checkpoint_the_search_does_not_replay_is_refused() {
        let task = tasks::by_name("cup").expect("the CUP task exists");
        let mut s = Settings::defaults(&task);
        s.method = Method::Adaptive;
        s.scale = Some(0.125);
        s.spp = 2;
        s.iterations = 10;
        let dir = std::env::temp_dir().join(format!("plateau-recount-bad-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let file = dir.join(checkpoint::FILE);
        let ctl = Control {
            checkpoint: Some(file.clone()),
            every: Every::End,
            ..Control::default()
        };
        optimize_with(&task, &s, ctl).expect("the run succeeds");
        let mut c = Checkpoint::load(&file).expect("its checkpoint");
        let Progress::Adaptive { points_hash, .. } = &mut c.progress else {
            panic!("an adaptive checkpoint")
        };
        *points_hash ^= 1;
        c.save(&file).expect("written");
        let err = recount(&file).expect_err("refused").to_string();
        assert!(err.contains("other points"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
