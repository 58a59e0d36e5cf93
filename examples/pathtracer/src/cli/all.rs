//! `all`: every task with the plateau-free gradient and the finite-difference baseline, then
//! `results.md` beside the paper's numbers.

use std::path::{Path, PathBuf};

use super::{summarize, values, with_threads};
use crate::report::Result;
use crate::run::{self, checkpoint, Control, Earlier, Every, Method, Settings};
use crate::tasks::{self, Task};

/// The options of `all`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Output directory.
    #[arg(long, default_value = "out", value_parser = values::out_dir)]
    out: PathBuf,
    /// A few minutes in all: a tenth of the iterations at half resolution.
    #[arg(long)]
    quick: bool,
    /// Only these tasks (comma-separated) [default: every task].
    #[arg(long, value_delimiter = ',', value_parser = values::task)]
    tasks: Option<Vec<String>>,
    /// Runs of the plateau-free gradient per task (seeds 0, 1, ...): the table reports
    /// the median and the range.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = values::at_least(1u64))]
    seeds: u64,
    /// The method of the runs: polished (the paper's loop, then the library's adaptive search
    /// from its best point, on the same evaluations), plateau (the paper's loop alone: the
    /// reproduction of Table 2) or adaptive (the library's Minimizer alone) [default:
    /// polished].
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// The stop rule of every run (as `optimize --stop-when-stalled`): end a run when its
    /// best value has not improved over this fraction of its renders (0.2 is the library's
    /// `STALL_WINDOW`) [default: off].
    #[arg(long, value_name = "FRACTION", allow_hyphen_values = true, value_parser = values::fraction)]
    stop_when_stalled: Option<f64>,
    /// With --method polished (the default): the share of every run's renders that the
    /// adaptive search gets after the paper's loop (as `optimize --polish`) [default: 0.5].
    #[arg(long, value_name = "FRACTION", allow_hyphen_values = true, value_parser = values::share)]
    polish: Option<f64>,
    /// Skip the finite-difference baseline.
    #[arg(long)]
    no_baseline: bool,
    /// Worker threads for rendering [default: all cores].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    threads: Option<usize>,
    /// Testing: stop each run as Ctrl-C does once this many iterations are done [default:
    /// never].
    #[arg(long, hide = true, value_name = "N", allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    stop_after: Option<usize>,
}

/// Runs every task (or those of `--tasks`), rewriting `results.md` after each.
pub(super) fn run(args: Args) -> Result<()> {
    let method = args.method.unwrap_or(Method::TASK_DEFAULT);
    super::check_polish(args.polish, method)?;
    with_threads(args.threads, || {
        all(
            &args.out,
            args.quick,
            args.tasks.as_deref(),
            args.seeds,
            Runs {
                method,
                stall: args.stop_when_stalled,
                polish: args.polish,
            },
            !args.no_baseline,
            &Limits {
                stop_after: args.stop_after,
                shrink: None,
            },
        )
    })
}

/// What every run of `all` is: its method, its stop rule (`--stop-when-stalled`) and, if
/// given, the polish's share (`--polish`).
struct Runs {
    method: Method,
    stall: Option<f64>,
    polish: Option<f64>,
}

/// What a test changes of `all`: when to stop each run, and a change of every run's
/// settings (to make them small).
struct Limits {
    stop_after: Option<usize>,
    shrink: Option<fn(&mut Settings)>,
}

/// Runs `task` with `s` into `dir`, unless `dir` holds the finished run of these settings
/// (kept); continues it if `dir` holds its unfinished run. An interrupted run returns
/// [`Interrupted`](crate::run::interrupt::Interrupted) (the command line then exits 130; the same command continues).
fn run_in(task: &Task, s: &Settings, dir: &Path, limits: &Limits) -> Result<()> {
    let path = dir.join(checkpoint::FILE);
    let earlier = Earlier::at(&path, task, s);
    if let Earlier::Finished(c) = &earlier {
        if summary_complete(dir) {
            eprintln!(
                "{}: kept (finished, {} iterations)",
                dir.display(),
                c.history.len()
            );
            return Ok(());
        }
    }
    let (resume, settings) = earlier.resume(&dir.display().to_string(), s);
    let control = Control {
        out: Some(dir),
        checkpoint: Some(path),
        every: Every::Auto,
        resume,
        requested: Some(s.clone()),
        stop_after: limits.stop_after,
        progress: limits.shrink.is_none(),
    };
    run::optimize_with(task, &settings, control)?.unless_interrupted()?;
    Ok(())
}

/// Whether `dir` holds the summary of a run that was not interrupted.
fn summary_complete(dir: &Path) -> bool {
    std::fs::read(dir.join("summary.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<run::Summary>(&b).ok())
        .is_some_and(|s| !s.interrupted)
}

/// Every task with the plateau-free gradient and, where it is affordable, the finite-difference
/// baseline; then `results.md`.
fn all(
    out: &Path,
    quick: bool,
    only: Option<&[String]>,
    seeds: u64,
    runs: Runs,
    baseline: bool,
    limits: &Limits,
) -> Result<()> {
    let command = format!(
        "cargo run --release -p pathtracer -- all{}{} --method {}{}{}{}{} --out {}",
        if quick { " --quick" } else { "" },
        if seeds > 1 {
            format!(" --seeds {seeds}")
        } else {
            String::new()
        },
        runs.method.as_arg(),
        runs.stall
            .map_or(String::new(), |f| format!(" --stop-when-stalled {f}")),
        runs.polish
            .map_or(String::new(), |f| format!(" --polish {f}")),
        if baseline { "" } else { " --no-baseline" },
        only.map_or(String::new(), |t| format!(" --tasks {}", t.join(","))),
        out.display()
    );
    for task in tasks::all() {
        if only.is_some_and(|names| !names.iter().any(|n| n == task.name())) {
            continue;
        }
        let mut plateau = Settings::defaults(&task);
        plateau.method = runs.method;
        plateau.stall = runs.stall;
        plateau.polish = runs.polish.unwrap_or(plateau.polish);
        if quick {
            plateau.iterations = (plateau.iterations / 10).max(20);
            plateau.eval_every = run::eval_every(plateau.iterations, 20);
            plateau.scale = Some(0.5);
        }
        if let Some(shrink) = limits.shrink {
            shrink(&mut plateau);
        }
        for seed in 0..seeds {
            let mut s = plateau.clone();
            s.seed = seed;
            let dir = match seed {
                0 => out.join(task.name()),
                k => out.join(format!("{}-seed{k}", task.name())),
            };
            run_in(&task, &s, &dir, limits)?;
        }
        // Central differences cost 2n renders per iteration: affordable for the
        // low-dimensional tasks only (SORT would need 300 renders an iteration).
        if baseline && task.dim() <= 8 {
            let mut fd = Settings {
                method: Method::Plateau,
                ..plateau.clone()
            };
            fd.method = Method::Fd;
            run_in(&task, &fd, &out.join(format!("{}-fd", task.name())), limits)?;
        }
        // Rewritten after every task, so that an interrupted run still leaves its table.
        summarize::write_results(out, &command)?;
    }
    println!("wrote {}", out.join("results.md").display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::interrupt::Interrupted;

    /// `history.csv` without its seconds, the summary's numbers without timings, the final
    /// image: what a resumed run must reproduce.
    fn results(dir: &Path) -> (String, String, Vec<u8>) {
        let history = std::fs::read_to_string(dir.join("history.csv")).unwrap();
        let history = history
            .lines()
            .map(|l| l.rsplit_once(',').map_or(l, |(a, _)| a).to_string())
            .collect::<Vec<_>>()
            .join("\n");
        let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
        let summary = summary
            .lines()
            .filter(|l| !l.contains("seconds"))
            .collect::<Vec<_>>()
            .join("\n");
        (
            history,
            summary,
            std::fs::read(dir.join("final.exr")).unwrap(),
        )
    }

    /// Interrupted mid-way, `all` keeps its finished runs (not run again: their files are
    /// untouched) and continues the interrupted one; everything ends as in an `all` left
    /// alone.
    #[test]
    fn all_keeps_finished_runs_and_resumes_the_rest() {
        fn small(s: &mut Settings) {
            s.iterations = 8;
            s.eval_every = 2;
            s.spp = 2;
            s.scale = Some(0.125);
        }
        let root = std::env::temp_dir().join(format!("plateau-all-resume-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let only = ["shadow".to_string()];
        let go = |out: &Path, seeds: u64, stop_after: Option<usize>| {
            let limits = Limits {
                stop_after,
                shrink: Some(small),
            };
            all(
                out,
                false,
                Some(&only),
                seeds,
                Runs {
                    method: Method::Plateau,
                    stall: None,
                    polish: None,
                },
                true,
                &limits,
            )
        };
        let alone = root.join("alone");
        go(&alone, 2, None).unwrap();

        let cut = root.join("cut");
        go(&cut, 1, None).unwrap(); // seed 0 and the baseline finish
        let first = std::fs::read(cut.join("shadow/summary.json")).unwrap();
        let fd = std::fs::read(cut.join("shadow-fd/summary.json")).unwrap();
        let err = go(&cut, 2, Some(3)).unwrap_err(); // seed 1 is interrupted
        assert!(err.is::<Interrupted>(), "{err}");
        assert_eq!(
            std::fs::read(cut.join("shadow/summary.json")).unwrap(),
            first
        );
        let seed1 = std::fs::read_to_string(cut.join("shadow-seed1/summary.json")).unwrap();
        assert!(seed1.contains("\"interrupted\": true"));
        go(&cut, 2, None).unwrap();
        // Kept, not run again (a new run would have new timings).
        assert_eq!(
            std::fs::read(cut.join("shadow/summary.json")).unwrap(),
            first
        );
        assert_eq!(
            std::fs::read(cut.join("shadow-fd/summary.json")).unwrap(),
            fd
        );
        for run in ["shadow", "shadow-seed1", "shadow-fd"] {
            assert_eq!(
                results(&alone.join(run)),
                results(&cut.join(run)),
                "{run} differs"
            );
        }
        let _ = std::fs::remove_dir_all(&root);
    }
}
