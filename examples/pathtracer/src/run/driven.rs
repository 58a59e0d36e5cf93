//! Every method of a run as one ask-and-tell method for the library's
//! [`plateau_free::lifecycle::Driver`]: [`Tracked`] wraps the library's method
//! ([`Progress`]) with what the path tracer keeps besides (the rest of a [`Checkpoint`]:
//! the history, the progress strip's points, every value told, the renders, the times), so
//! that the library's driver runs it, its checkpoint saves and resumes it whole (the
//! identity adds the task, the settings and the build), and its observers show it.

use std::cell::Cell;
use std::time::{Duration, Instant};

use plateau_free::lifecycle::AskAndTell;
use plateau_free::{run::History, Ask, Error};

use super::checkpoint::{executable, Checkpoint, Progress};
use super::{Ended, Row, Settings};
use crate::render::Image;
use crate::tasks::Task;

/// What a run's method needs and does not save: the task, the settings, the reference, the
/// start, the loss and its counters.
pub(super) struct Ctx<'a> {
    pub task: &'a Task,
    pub s: &'a Settings,
    pub reference: &'a Image,
    pub start: &'a [f64],
    pub target: Vec<f64>,
    /// The image loss at a point with a renderer seed (it counts and times its renders).
    pub loss: &'a dyn Fn(&[f64], u64) -> f64,
    pub renders: &'a Cell<usize>,
    pub render_time: &'a Cell<Duration>,
}

/// How a run ended, its final point, its history, six snapshots for the progress strip and
/// the optimisation time: what every method hands to the outputs.
pub(super) struct Finished {
    pub ended: Ended,
    pub theta: Vec<f64>,
    pub history: Vec<Row>,
    pub snapshots: Vec<Vec<f64>>,
    pub time: Duration,
}

/// A run's method with the path tracer's record of it (see the module's text).
pub(super) struct Tracked<'a> {
    pub(super) saved: Checkpoint,
    ctx: &'a Ctx<'a>,
    /// The points of the ask waiting for its values, flat (the searches).
    pub(super) asked: Vec<f64>,
    /// When the ask waiting for its values was made.
    asked_at: Option<Instant>,
}

impl<'a> Tracked<'a> {
    /// A fresh run of `progress` under `ctx`, asked for with the settings `requested`.
    pub(super) fn new(ctx: &'a Ctx<'a>, progress: Progress, requested: &Settings) -> Self {
        let saved = Checkpoint {
            task: ctx.task.name().into(),
            requested: requested.clone(),
            settings: ctx.s.clone(),
            finished: false,
            progress,
            history: Vec::new(),
            snapshots: vec![ctx.start.to_vec()],
            values: Vec::new(),
            best_value: None,
            best_point: ctx.start.to_vec(),
            renders: 0,
            optimisation_seconds: 0.0,
            render_seconds: 0.0,
        };
        Tracked {
            saved,
            ctx,
            asked: Vec::new(),
            asked_at: None,
        }
    }

    /// Whether the time budget (the paper's loop) is spent.
    fn over_time(&self) -> bool {
        let c = &self.saved;
        c.settings
            .budget_seconds
            .is_some_and(|b| c.optimisation_seconds >= b)
    }

    /// The end of the run (`interrupted`: stopped before it, to be continued).
    fn output(&self, interrupted: bool) -> Finished {
        let c = &self.saved;
        let (iterations, evaluations, theta, stalled) = match &c.progress {
            Progress::Loop(run) => (
                run.iteration(),
                run.history().evaluations,
                run.theta().to_vec(),
                false,
            ),
            Progress::Baseline(run) => (
                run.iteration(),
                run.history().evaluations,
                run.theta().to_vec(),
                false,
            ),
            Progress::Adaptive(search) => match search.result() {
                Some(m) if !interrupted => {
                    let stalled = m.stop == plateau_free::Stop::Stalled;
                    (m.iterations, m.evaluations, m.x.clone(), stalled)
                }
                _ => (
                    c.history.len(),
                    search.evaluations(),
                    c.best_point.clone(),
                    false,
                ),
            },
            Progress::Image(m) => {
                let best = m.result();
                (c.history.len(), best.nfev, best.x, false)
            }
        };
        let loops = matches!(c.progress, Progress::Loop(_) | Progress::Baseline(_));
        let stopped_early = if loops {
            !interrupted && iterations < c.settings.iterations
        } else {
            stalled
        };
        Finished {
            ended: Ended {
                iterations,
                evaluations,
                renders: c.renders,
                stopped_early,
                interrupted,
            },
            snapshots: self.strip(&theta, interrupted),
            theta,
            history: c.history.clone(),
            time: Duration::from_secs_f64(c.optimisation_seconds),
        }
    }
}

impl AskAndTell for Tracked<'_> {
    type Output = Finished;

    fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        if self.saved.finished || self.over_time() {
            self.saved.finished = true;
            return Ok(None);
        }
        self.asked_at = Some(Instant::now());
        let search = matches!(self.saved.progress, Progress::Adaptive(_));
        let ask = match &mut self.saved.progress {
            Progress::Loop(run) => run.ask()?,
            Progress::Adaptive(search) => search.ask()?,
            Progress::Baseline(run) => run.ask()?,
            Progress::Image(m) => m.ask()?,
        };
        match ask {
            None => {
                self.saved.finished = true;
                Ok(None)
            }
            Some(ask) => {
                self.asked.clear();
                if search {
                    self.asked.extend_from_slice(ask.points().as_flat());
                }
                Ok(Some(ask))
            }
        }
    }

    fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        let ctx = self.ctx;
        let step = match &mut self.saved.progress {
            Progress::Loop(run) => {
                let before = run.iteration();
                run.tell(values)?;
                (run.iteration() > before)
                    .then(|| step(run.history(), run.theta(), run.last_estimate()))
            }
            Progress::Baseline(run) => {
                run.tell(values)?;
                Some(step(run.history(), run.theta(), run.last_estimate()))
            }
            Progress::Adaptive(search) => {
                search.tell(values)?;
                None
            }
            Progress::Image(m) => {
                m.tell(values)?;
                None
            }
        };
        let spent = self.asked_at.take().map_or(Duration::ZERO, |t| t.elapsed());
        self.saved.optimisation_seconds += spent.as_secs_f64();
        self.saved.renders = ctx.renders.get();
        self.saved.render_seconds = ctx.render_time.get().as_secs_f64();
        match (&self.saved.progress, step) {
            (Progress::Adaptive(_), _) => self.record_search(ctx, values),
            (Progress::Image(_), _) => self.record_image(ctx),
            (_, Some((theta, sigma, loss))) => self.record_loop(ctx, &theta, sigma, loss),
            (_, None) => {}
        }
        Ok(())
    }

    fn values_per_point(&self) -> usize {
        match &self.saved.progress {
            Progress::Image(m) => m.outputs(),
            _ => 1,
        }
    }

    fn evaluations(&self) -> usize {
        self.saved.renders
    }

    fn budget(&self) -> Option<usize> {
        let s = &self.saved.settings;
        match self.saved.progress {
            Progress::Adaptive(_) | Progress::Image(_) => {
                Some(s.samples.saturating_mul(s.iterations))
            }
            _ => None,
        }
    }

    fn iteration(&self) -> usize {
        self.saved.history.len()
    }

    fn sigma(&self) -> f64 {
        self.saved.history.last().map_or(f64::NAN, |r| r.sigma)
    }

    fn best_value(&self) -> f64 {
        match (&self.saved.progress, self.saved.best_value) {
            (Progress::Adaptive(_), best) => best.unwrap_or(f64::INFINITY),
            _ => self.saved.history.last().map_or(f64::INFINITY, |r| r.loss),
        }
    }

    fn failures(&self) -> usize {
        match &self.saved.progress {
            Progress::Adaptive(search) => AskAndTell::failures(&**search),
            Progress::Image(m) => AskAndTell::failures(&**m),
            _ => 0,
        }
    }

    fn finish(self) -> Result<Finished, Error> {
        Ok(self.output(false))
    }

    fn so_far(&self) -> Finished {
        self.output(!self.saved.finished)
    }

    fn identity(&self) -> Vec<(&'static str, String)> {
        let json = |s: &Settings| serde_json::to_string(s).unwrap_or_default();
        vec![
            ("task", self.saved.task.clone()),
            ("requested", json(&self.saved.requested)),
            ("settings", json(&self.saved.settings)),
            ("executable", executable()),
        ]
    }

    fn save(&self, out: &mut Vec<u8>) -> Result<(), Error> {
        serde_json::to_writer(out, &self.saved).map_err(|e| Error::Checkpoint {
            path: String::new(),
            reason: format!("state not written: {e}"),
        })
    }

    /// The saved record and method replace this run's; the task, the loss and its counters
    /// (not saved) stay, the counters set to the record's.
    fn restore(&mut self, bytes: &[u8]) -> Result<(), Error> {
        let path = std::path::Path::new("");
        self.saved = Checkpoint::parse(bytes, path).map_err(|e| Error::Checkpoint {
            path: String::new(),
            reason: e.to_string(),
        })?;
        self.ctx.renders.set(self.saved.renders);
        let seconds = Duration::from_secs_f64(self.saved.render_seconds);
        self.ctx.render_time.set(seconds);
        Ok(())
    }
}

/// A completed iteration of the paper's loop: theta after its step, the spread it estimated
/// with, its estimate's mean value.
fn step(
    history: &History,
    theta: &[f64],
    estimate: Option<&plateau_free::Estimate>,
) -> (Vec<f64>, f64, f64) {
    let sigma = history.sigma.last().copied().unwrap_or(f64::NAN);
    let loss = estimate.map_or(f64::NAN, |e| e.mean_value);
    (theta.to_vec(), sigma, loss)
}
