//! A long run of the paper's loop keeps its memory bounded (`iterations=10**12` must not grow
//! with the per-iteration history). Its own file, so that it runs in its own
//! process (the peak resident memory is the process's) and in parallel with the others.
// Linux alone has `/proc/self/status`; CI runs on Linux, where a missing value fails the test.
#![cfg(target_os = "linux")]

use plateau_free::{run::HistoryKeep, Adam, Annealer, Optimizer, PlateauFreeGradient};

/// The peak resident memory of the process so far, in kB (`VmHWM`), where `/proc` has it.
fn peak_resident_kb() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[test]
fn ten_million_iterations_stay_under_100_mb_with_the_default_history() {
    let before = peak_resident_kb().expect("VmHWM in /proc/self/status");
    const ITERATIONS: usize = 10_000_000;
    let mut grad = PlateauFreeGradient::new(|x: &[f64]| x[0] * x[0]).samples(2);
    let mut opt = Optimizer::new(
        Adam::new(1e-3).unwrap(),
        Annealer::constant(0.1, ITERATIONS).unwrap(),
    );
    let history = opt.minimize(&mut grad, &[1.0]).unwrap();
    let after = peak_resident_kb().expect("VmHWM in /proc/self/status");
    assert_eq!(history.iterations(), ITERATIONS);
    assert_eq!(history.evaluations, 2 * ITERATIONS);
    assert_eq!(history.sigma.len(), HistoryKeep::DEFAULT_LAST);
    assert_eq!(history.value.len(), HistoryKeep::DEFAULT_LAST);
    assert_eq!(history.dropped, ITERATIONS - HistoryKeep::DEFAULT_LAST);
    let grown_mb = (after.saturating_sub(before)) as f64 / 1024.0;
    assert!(
        grown_mb < 100.0,
        "the peak resident memory grew by {grown_mb:.1} MB over {ITERATIONS} iterations"
    );
}
