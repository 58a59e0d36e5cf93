//! How an estimate's points are evaluated: in order, or on rayon's pool, with or without
//! catching a panic of the objective.

use std::any::Any;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use rayon::prelude::*;

use super::Panic;
use crate::objective::{Objective, Points};

/// One estimate's points, the objective's seed for each, and the values to fill in: what an
/// evaluator gets.
pub(super) struct Batch<'a> {
    pub(super) points: Points<'a>,
    pub(super) seeds: &'a [u64],
    pub(super) out: &'a mut [f64],
}

/// A panic's message, cut to 200 characters (a payload that is not text is named as such).
pub(super) fn panic_message(payload: &(dyn Any + Send)) -> String {
    let text = if let Some(s) = payload.downcast_ref::<&str>() {
        s
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.as_str()
    } else {
        "(a panic payload that is not text)"
    };
    const LIMIT: usize = 200;
    match text.char_indices().nth(LIMIT) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text.to_owned(),
    }
}

pub(super) fn evaluate_sequential<F: Objective>(
    f: &F,
    b: Batch<'_>,
    catch: bool,
) -> Result<(), Panic> {
    let Batch { points, seeds, out } = b;
    if catch {
        // Unwind safety: `out` is scratch that every estimate overwrites before reading, and
        // the estimator's counter is already advanced; nothing half-written is used again.
        catch_unwind(AssertUnwindSafe(|| f.evaluate_batch(points, seeds, out)))
    } else {
        f.evaluate_batch(points, seeds, out);
        Ok(())
    }
}

pub(super) fn evaluate_parallel<F: Objective + Sync>(
    f: &F,
    b: Batch<'_>,
    catch: bool,
) -> Result<(), Panic> {
    let Batch { points, seeds, out } = b;
    if !catch {
        out.par_iter_mut()
            .enumerate()
            .for_each(|(i, o)| *o = f.evaluate(points.get(i), seeds[i]));
        return Ok(());
    }
    // Each point is caught on its own thread; once one has panicked the points not yet
    // started are skipped, so that a failing objective is not run (and its panic message
    // printed) once per point.
    let panicked = AtomicBool::new(false);
    let first: Mutex<Option<Panic>> = Mutex::new(None);
    out.par_iter_mut().enumerate().for_each(|(i, o)| {
        if panicked.load(Ordering::Relaxed) {
            return;
        }
        match catch_unwind(AssertUnwindSafe(|| f.evaluate(points.get(i), seeds[i]))) {
            Ok(v) => *o = v,
            Err(payload) => {
                panicked.store(true, Ordering::Relaxed);
                let mut slot = first.lock().unwrap_or_else(|e| e.into_inner());
                slot.get_or_insert(payload);
            }
        }
    });
    match first.into_inner().unwrap_or_else(|e| e.into_inner()) {
        Some(payload) => Err(payload),
        None => Ok(()),
    }
}
