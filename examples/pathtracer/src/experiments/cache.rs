//! The experiments' run cache: `<out>/runs/`, one JSON file per run.
//!
//! The experiments share many runs (the task defaults are the full method of the ablation,
//! the radial sampler of the sampler study, the base of the trade-off, N = 2 of Fig. 2), and
//! runs are deterministic, so each is made once. `runs/` is not committed: a clean checkout
//! recomputes everything.

use std::fs;
use std::path::Path;

use super::Options;
use crate::report::Result;
use crate::run::{self, Control, Earlier, Outcome, Settings};
use crate::tasks::Task;

/// Runs `task` with `s` (no outputs, no progress bar; one line on stderr), or reads the run
/// back from `<out>/runs/` when this very binary made it before with the same settings. The
/// key is the task and every setting; the entry also holds a hash of the executable, so any
/// change of code misses the cache instead of reusing a stale run (`--reuse-runs` waives
/// that check).
pub(super) fn optimize(opts: &Options, task: &Task, s: &Settings) -> Result<Outcome> {
    let key = format!("{} {:?}", task.name(), s);
    let file = opts.out.join("runs").join(format!(
        "{}-{:016x}.json",
        task.name(),
        fnv1a(key.as_bytes())
    ));
    let build = executable_hash();
    let cached = fs::read(&file)
        .ok()
        .and_then(|bytes| serde_json::from_slice::<CachedRun>(&bytes).ok())
        .filter(|c| c.key == key && (opts.reuse_runs || Some(c.build) == build));
    let (outcome, source) = match cached {
        Some(c) => (c.outcome, "cached"),
        None => {
            let outcome =
                run_with_checkpoint(opts, task, s, &file.with_extension("checkpoint.json"))?;
            if let Some(build) = build {
                let entry = CachedRun {
                    key,
                    build,
                    outcome,
                };
                fs::create_dir_all(file.parent().expect("runs/ has a parent"))?;
                // Write then rename, so a concurrent experiment never reads half a file.
                let tmp = file.with_extension(format!("tmp{}", std::process::id()));
                fs::write(&tmp, serde_json::to_vec(&entry)?)?;
                fs::rename(&tmp, &file)?;
                (entry.outcome, "ran")
            } else {
                (outcome, "ran")
            }
        }
    };
    let m = &outcome.summary;
    eprintln!(
        "  {:>9} {:<32} N={:<2} spp={:<3} sigma0={:<5} seed={} -> param MSE {:.3e}, image MSE {:.3e}, {:.4} s/it ({source})",
        m.task,
        s.label(),
        s.samples,
        s.spp,
        s.sigma0,
        s.seed,
        m.param_mse,
        m.image_mse,
        m.seconds_per_iteration
    );
    Ok(outcome)
}

/// Runs `task` with `s`, writing its checkpoint to `path` now and then, continuing the
/// unfinished run `path` holds (Ctrl-C during an experiment), and removing `path` once the
/// run is done (the cache entry then keeps it). An interrupted run returns
/// [`Interrupted`](crate::run::interrupt::Interrupted).
fn run_with_checkpoint(opts: &Options, task: &Task, s: &Settings, path: &Path) -> Result<Outcome> {
    let (resume, settings) = Earlier::at(path, task, s).resume(&format!("  {}", task.name()), s);
    let control = Control {
        checkpoint: Some(path.to_path_buf()),
        resume,
        requested: Some(s.clone()),
        stop_after: opts.stop_after,
        ..Control::default()
    };
    let outcome = run::optimize_with(task, &settings, control)?.unless_interrupted()?;
    let _ = fs::remove_file(path);
    Ok(outcome)
}

/// One entry of the run cache.
#[derive(serde::Serialize, serde::Deserialize)]
struct CachedRun {
    key: String,
    build: u64,
    outcome: Outcome,
}

use crate::run::checkpoint::{executable_hash, fnv1a};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::quick_options;
    use crate::run::interrupt::Interrupted;

    /// SHADOW at 1/64 of the pixels and 2 spp, for `iterations`: a run of a few seconds.
    fn tiny_shadow(iterations: usize) -> (Task, Settings) {
        let t = super::super::task("shadow").unwrap();
        let mut s = Settings::defaults(&t);
        s.iterations = iterations;
        s.spp = 2;
        s.scale = Some(0.125);
        (t, s)
    }

    /// A second identical run is read back (its measured seconds are the first run's, which a
    /// new run would not repeat); another setting is a new run.
    #[test]
    fn runs_are_cached_by_settings() {
        let opts = quick_options("cache");
        let out = opts.out.clone();
        let (t, mut s) = tiny_shadow(3);
        let first = optimize(&opts, &t, &s).unwrap();
        let again = optimize(&opts, &t, &s).unwrap();
        assert_eq!(first.summary.seconds_total, again.summary.seconds_total);
        assert_eq!(first.summary.param_mse, again.summary.param_mse);
        assert_eq!(first.history.len(), again.history.len());
        s.seed = 1;
        let other = optimize(&opts, &t, &s).unwrap();
        assert_ne!(first.summary.seconds_total, other.summary.seconds_total);
        assert_eq!(fs::read_dir(out.join("runs")).unwrap().count(), 2);
        let _ = fs::remove_dir_all(&out);
    }

    /// An experiment interrupted in a run (Ctrl-C, here `stop_after`) keeps the runs it
    /// finished (cached) and the interrupted run's checkpoint; run again, it continues that
    /// run, which ends as the run left alone.
    #[test]
    fn an_interrupted_run_of_an_experiment_is_continued() {
        let mut opts = quick_options("cache-resume");
        let out = opts.out.clone();
        let (t, s) = tiny_shadow(8);
        let alone = run::optimize(&t, &s, None, false).unwrap();
        opts.stop_after = Some(3);
        let err = optimize(&opts, &t, &s).err().expect("interrupted");
        assert!(err.is::<Interrupted>(), "{err}");
        let runs: Vec<_> = fs::read_dir(out.join("runs"))
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert!(
            runs.len() == 1 && runs[0].ends_with(".checkpoint.json"),
            "{runs:?}"
        );
        opts.stop_after = None;
        let resumed = optimize(&opts, &t, &s).unwrap();
        assert_eq!(resumed.summary.param_mse, alone.summary.param_mse);
        assert_eq!(resumed.summary.image_mse, alone.summary.image_mse);
        let values = |o: &Outcome| {
            o.history
                .iter()
                .map(|r| (r.loss, r.param_mse, r.image_mse))
                .collect::<Vec<_>>()
        };
        assert_eq!(values(&resumed), values(&alone));
        // The checkpoint is gone, the cache entry is there.
        let runs: Vec<_> = fs::read_dir(out.join("runs")).unwrap().collect();
        assert_eq!(runs.len(), 1);
        let _ = fs::remove_dir_all(&out);
    }
}
