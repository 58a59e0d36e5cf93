//! Checkpoint files beyond `tests/lifecycle.rs`'s: the vector method resumed bit for bit;
//! a path that cannot be written fails the run before any evaluation; a write that fails
//! during the run (a full disk, a folder removed) is told to the observers and the run goes
//! on, as it would without a checkpoint.
#![cfg(feature = "serde")]

mod common;

use std::path::PathBuf;

use common::StopAt;
use plateau_free::lifecycle::{
    Checkpoint, Driver, Interrupt, Observer, Progress, ProgressLine, Workers,
};
use plateau_free::vector::Sparsity;
use plateau_free::{Ask, Error, LeastSquares, Minimizer};

/// A plain objective, as a function pointer (one type for every run of a test).
type Plain = fn(&[f64]) -> f64;

fn sphere(x: &[f64]) -> f64 {
    x.iter().map(|v| (v - 0.3) * (v - 0.3)).sum()
}

/// A fresh folder of this test process.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "plateau-free-checkpoint-writes-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Counts the writes the driver could not make.
#[derive(Default)]
struct NotSaved(usize);

impl Observer for NotSaved {
    fn observe(&mut self, _: &Progress) {}

    fn not_saved(&mut self, error: &Error) {
        assert!(matches!(error, Error::Checkpoint { .. }), "{error}");
        self.0 += 1;
    }
}

#[test]
fn a_path_that_cannot_be_written_fails_before_any_evaluation() {
    let path = folder("missing").join("no-such-folder").join("run.json");
    let m = Minimizer::new(sphere as Plain).budget(500).seed(1);
    let mut evaluated = 0;
    let failure = Driver::new()
        .checkpoint(Checkpoint::new(&path))
        .run(m.ask_tell(&[0.0; 3]).unwrap(), |w, ask, out| {
            evaluated += ask.len();
            w.evaluate(&(sphere as Plain), ask, out)
        })
        .unwrap_err();
    assert_eq!(evaluated, 0);
    let message = failure.error.to_string();
    assert!(
        message.contains("run.json") && message.contains("not written"),
        "{message}"
    );
}

#[test]
fn a_write_that_fails_during_the_run_is_told_and_the_run_goes_on() {
    // The folder is removed at turn 10 and made again at turn 40: the writes due between
    // fail, each told once; the run is the run left alone, and its last file resumes to it.
    let dir = folder("removed");
    let path = dir.join("run.json");
    let x0 = [-1.0, 0.5, 2.0];
    let m = Minimizer::new(sphere as Plain).budget(600).seed(2);
    let alone = m.run(&x0).unwrap();
    let mut told = NotSaved::default();
    let mut turn = 0;
    let driven = Driver::new()
        .observe(&mut told)
        .checkpoint(Checkpoint::new(&path).every_iterations(5))
        .run(m.ask_tell(&x0).unwrap(), |w, ask, out| {
            turn += 1;
            match turn {
                10 => std::fs::remove_dir_all(&dir).unwrap(),
                40 => std::fs::create_dir_all(&dir).unwrap(),
                _ => {}
            }
            w.evaluate(&(sphere as Plain), ask, out)
        })
        .unwrap();
    assert_eq!(driven, alone);
    // Writes are due every 5 iterations; those from turn 10 to 39 fail (iterations 9-38).
    assert!((5..=7).contains(&told.0), "{} writes told", told.0);
    let resumed = m
        .run_with(&x0, Driver::new().checkpoint(Checkpoint::new(&path)))
        .unwrap();
    assert_eq!(resumed, alone);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_progress_line_warns_of_a_write_that_failed() {
    let dir = folder("warned");
    let path = dir.join("run.json");
    let m = Minimizer::new(sphere as Plain).budget(200).seed(3);
    let mut out = Vec::new();
    let mut turn = 0;
    let failure = Driver::new()
        .observe(ProgressLine::new(&mut out))
        .checkpoint(Checkpoint::new(&path).every_iterations(1))
        .run(m.ask_tell(&[1.0, 1.0]).unwrap(), |w, ask, out| {
            turn += 1;
            if turn == 3 {
                std::fs::remove_dir_all(&dir).unwrap();
            }
            w.evaluate(&(sphere as Plain), ask, out)
        })
        .unwrap_err();
    // The run went on to its end, where the last write failed too: the result is whole.
    let result = failure.result.expect("the result so far");
    assert_eq!(*result, m.run(&[1.0, 1.0]).unwrap());
    let text = String::from_utf8(out).unwrap();
    assert!(
        text.contains("warning: checkpoint") && text.contains("the run goes on"),
        "{text}"
    );
}

#[test]
fn least_squares_resumes_bit_for_bit() {
    // Residuals with failures (a NaN output past x0 > 0.8) and a box: the saved state
    // keeps the damping, the averaged Jacobian and the failed pairs' count.
    let r = |x: &[f64], _: u64, out: &mut [f64]| {
        out[0] = x[0] - 1.5;
        out[1] = if x[0] > 0.8 {
            f64::NAN
        } else {
            2.0 * (x[1] + 0.5)
        };
        out[2] = x[0] * x[1];
    };
    let ls = LeastSquares::new(Sparsity::dense(3, 2).unwrap())
        .budget(300)
        .bounds(vec![-2.0, -2.0], vec![2.0, 2.0])
        .seed(4);
    let run = || ls.ask_tell(&[0.0, 0.0]).unwrap();
    let evaluate = |w: &Workers, ask: Ask<'_>, out: &mut [f64]| w.evaluate_rows(&r, ask, 3, out);
    let alone = Driver::new().run(run(), evaluate).unwrap();
    assert!(alone.failures > 0, "{alone:?}");
    let path = folder("least-squares").join("run.json");
    let stop = Interrupt::new();
    let first = Driver::new()
        .interrupt(stop.clone())
        .observe(StopAt(6, stop))
        .checkpoint(Checkpoint::new(&path))
        .run(run(), evaluate)
        .unwrap();
    assert!(first.nfev < alone.nfev);
    let resumed = Driver::new()
        .checkpoint(Checkpoint::new(&path))
        .run(run(), evaluate)
        .unwrap();
    assert_eq!(resumed, alone);
    let other = ls.clone().seed(5).ask_tell(&[0.0, 0.0]).unwrap();
    let refused = Driver::new()
        .checkpoint(Checkpoint::new(&path))
        .run(other, evaluate)
        .unwrap_err();
    assert!(
        refused.error.to_string().contains("options"),
        "{}",
        refused.error
    );
}
