//! The experiments' run cache: `<out>/runs/`, one JSON file per run.
//!
//! The experiments share many runs (the task defaults are the full method of the ablation,
//! the radial sampler of the sampler study, the base of the trade-off, N = 2 of Fig. 2), and
//! runs are deterministic, so each is made once. `runs/` is not committed: a clean checkout
//! recomputes everything.

use std::fs;

use super::Options;
use crate::report::Result;
use crate::run::{self, Outcome, Settings};
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
            let outcome = run::optimize(task, s, None, false)?;
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

/// One entry of the run cache.
#[derive(serde::Serialize, serde::Deserialize)]
struct CachedRun {
    key: String,
    build: u64,
    outcome: Outcome,
}

/// A hash of the running executable (`None` if it cannot be read: then nothing is cached).
fn executable_hash() -> Option<u64> {
    static HASH: std::sync::OnceLock<Option<u64>> = std::sync::OnceLock::new();
    *HASH.get_or_init(|| {
        let exe = std::env::current_exe().ok()?;
        fs::read(exe).ok().map(|bytes| fnv1a(&bytes))
    })
}

/// 64-bit FNV-1a: stable across runs and Rust versions, unlike `DefaultHasher`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::quick_options;

    /// A second identical run is read back (its measured seconds are the first run's, which a
    /// new run would not repeat); another setting is a new run.
    #[test]
    fn runs_are_cached_by_settings() {
        let opts = quick_options("cache");
        let out = opts.out.clone();
        let t = super::super::task("shadow").unwrap();
        let mut s = Settings::defaults(&t);
        s.iterations = 3;
        s.spp = 2;
        s.scale = Some(0.125);
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
}
