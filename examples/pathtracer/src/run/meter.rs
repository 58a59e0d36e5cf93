//! A run's progress as it goes: on a terminal, a bar on stderr; elsewhere (stderr sent to a
//! file or a pipe, as in a batch job), a plain line on stderr every few seconds:
//!
//! ```text
//! shadow: iteration 40/150, renders 80, best loss 1.234e-3, elapsed 10 s
//! ```
//!
//! An iteration is a step of the method (an iteration of the paper's loop, a generation of
//! the adaptive search, a Jacobian or a step of the image method); renders are the renders of
//! the objective. The line's spacing is [`LINE_SECONDS`], or the seconds in the environment
//! variable [`LINE_SECONDS_VAR`] (0: a line after every iteration).

use std::cell::Cell;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Seconds between two plain progress lines: the library's [`plateau_free::lifecycle::ProgressLine`] spacing.
pub const LINE_SECONDS: f64 = plateau_free::lifecycle::PROGRESS_SECONDS;

/// The environment variable that sets the seconds between two plain progress lines.
pub const LINE_SECONDS_VAR: &str = "PATHTRACER_PROGRESS_SECONDS";

/// What a run's bar counts to its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Unit {
    /// Iterations (the paper's loop: their count is known ahead).
    Iterations,
    /// Renders of the objective (the adaptive search and the image method: their budget is
    /// known, their iterations are not).
    Renders,
}

impl Unit {
    fn name(self) -> &'static str {
        match self {
            Unit::Iterations => "iterations",
            Unit::Renders => "renders",
        }
    }
}

/// Where a run is, after an iteration.
#[derive(Clone, Copy, Debug)]
pub(super) struct At {
    /// Iterations done.
    pub iterations: usize,
    /// Renders of the objective so far.
    pub renders: usize,
    /// The iteration's loss (the lowest seen is shown).
    pub loss: f64,
}

/// The plain line's state.
struct Line {
    name: String,
    every: Duration,
    clock: Instant,
    last: Cell<Instant>,
    best: Cell<f64>,
}

/// A run's progress: a bar on a terminal, plain lines elsewhere, nothing if not shown.
pub(super) struct Meter {
    bar: ProgressBar,
    line: Option<Line>,
    unit: Unit,
    total: usize,
}

impl Meter {
    /// The progress of the run of task `name`, `total` of `unit` long (hidden unless `show`).
    pub(super) fn new(name: &str, total: usize, unit: Unit, show: bool) -> Meter {
        let terminal = std::io::stderr().is_terminal();
        let bar = if show && terminal {
            bar(name, total, unit)
        } else {
            ProgressBar::hidden()
        };
        let line = (show && !terminal).then(|| Line {
            name: name.into(),
            every: line_spacing(),
            clock: Instant::now(),
            last: Cell::new(Instant::now()),
            best: Cell::new(f64::INFINITY),
        });
        Meter {
            bar,
            line,
            unit,
            total,
        }
    }

    /// Moves the bar to `position` (of its unit) without a line: a resumed run's start.
    pub(super) fn set_position(&self, position: usize) {
        self.bar.set_position(position as u64);
    }

    /// Shows the run at `at`, with `message` beside the bar.
    pub(super) fn update(&self, at: At, message: String) {
        let position = match self.unit {
            Unit::Iterations => at.iterations,
            Unit::Renders => at.renders,
        };
        self.bar.set_position(position as u64);
        self.bar.set_message(message);
        let Some(line) = &self.line else { return };
        if at.loss < line.best.get() {
            line.best.set(at.loss);
        }
        if line.last.get().elapsed() < line.every {
            return;
        }
        line.last.set(Instant::now());
        let of = |unit| {
            if unit == self.unit {
                format!("/{}", self.total)
            } else {
                String::new()
            }
        };
        eprintln!(
            "{}: iteration {}{}, renders {}{}, best loss {:.3e}, elapsed {:.0} s",
            line.name,
            at.iterations,
            of(Unit::Iterations),
            at.renders,
            of(Unit::Renders),
            line.best.get(),
            line.clock.elapsed().as_secs_f64()
        );
    }

    /// Clears the bar.
    pub(super) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// The seconds between plain lines: [`LINE_SECONDS_VAR`]'s if it is a number >= 0, else
/// [`LINE_SECONDS`].
fn line_spacing() -> Duration {
    let seconds = std::env::var(LINE_SECONDS_VAR)
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .unwrap_or(LINE_SECONDS);
    Duration::from_secs_f64(seconds)
}

/// The terminal's bar of a run, counting `unit`.
fn bar(name: &str, total: usize, unit: Unit) -> ProgressBar {
    let bar = ProgressBar::new(total as u64);
    let template = format!(
        "{{prefix:>10}} [{{elapsed_precise}}] {{bar:32}} {{pos}}/{{len}} {} {{msg}} (ETA {{eta}})",
        unit.name()
    );
    let style =
        ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_prefix(name.to_string());
    bar
}
