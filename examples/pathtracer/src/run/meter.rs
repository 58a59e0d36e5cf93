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

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use plateau_free::lifecycle::{Observer, Progress};

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

/// The plain line's state.
struct Line {
    name: String,
    every: Duration,
    clock: Instant,
    last: Instant,
    best: f64,
}

/// A run's progress, shown by the library's driver after every iteration
/// ([`Observer`]: the iteration, the renders, the best value and the spread it reports): a
/// bar on a terminal, plain lines elsewhere, nothing if not shown.
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
            last: Instant::now(),
            best: f64::INFINITY,
        });
        Meter {
            bar,
            line,
            unit,
            total,
        }
    }
}

impl Observer for Meter {
    fn observe(&mut self, p: &Progress) {
        let position = match self.unit {
            Unit::Iterations => p.iteration,
            Unit::Renders => p.evaluations,
        };
        self.bar.set_position(position as u64);
        self.bar
            .set_message(format!("best {:.3e}  sigma {:.3}", p.best, p.sigma));
        let Some(line) = &mut self.line else { return };
        line.best = line.best.min(p.best);
        if line.last.elapsed() < line.every {
            return;
        }
        line.last = Instant::now();
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
            p.iteration,
            of(Unit::Iterations),
            p.evaluations,
            of(Unit::Renders),
            line.best,
            line.clock.elapsed().as_secs_f64()
        );
    }

    fn end(&mut self, _progress: &Progress) {
        self.bar.finish_and_clear();
    }

    fn not_saved(&mut self, error: &plateau_free::Error) {
        self.bar
            .suspend(|| eprintln!("warning: {error}; the run goes on"));
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
