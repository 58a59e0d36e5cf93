//! [`LeastSquares`]: damped Gauss-Newton on the Gaussian-smoothed residuals, written once as
//! an ask-and-tell run ([`LeastSquaresAskTell`]) with the callback forms on top.

use super::jacobian::{check_outputs, draw, pair_seed, Accumulator};
use super::solve::damped_step;
use super::{Acceptance, Sparsity, VectorMinimum};
use crate::check;
use crate::error::Error;
use crate::objective::Points;
use crate::run::{Ask, FailurePolicy};
use crate::seeding::stream_seed;
use crate::{anneal::PAPER_SIGMA_MIN, Annealer};

/// Options of the vector (least-squares) method: minimise `sum_i r_i(x)^2` for a black-box
/// `r: R^n -> R^m`, from values of `r` alone, by damped Gauss-Newton steps on the
/// Gaussian-smoothed residuals.
///
/// Each iteration draws `pairs` antithetic perturbations `tau ~ N(0, sigma^2 I)` (2 `pairs`
/// evaluations of `r`), estimates from them the smoothed Jacobian on the [`Sparsity`]
/// pattern (Stein's identity, [`crate::vector::smoothed_jacobian`]), averages it with the last
/// `memory - 1` estimates, solves `(J^T J + lambda diag(J^T J)) d = -J^T r` by conjugate
/// gradients (`r`: the current point's residuals, or the smoothed ones, see
/// [`LeastSquares::smoothed_residuals`]), limits each coordinate's move to `max_step`
/// sigmas, and evaluates the
/// step's point (one evaluation; see [`Acceptance`]). `sigma` is annealed over the budget as
/// the scalar method's ([`Annealer::paper`]: `sigma0` for half the evaluations, then linear
/// to 0.01, or to `sigma0` if smaller).
///
/// Assumptions: the pattern holds every dependence that matters (an output moving with a
/// parameter outside its row is ignored there); the outputs are deterministic given the
/// seed the run hands out (common random numbers within a pair and across step points).
///
/// ```
/// use plateau_free::{LeastSquares, vector::Sparsity};
/// // 1000 parameters, each seen by one output through a step function (a plateau).
/// let n = 1000;
/// let target: Vec<f64> = (0..n).map(|i| (i % 7) as f64 / 7.0).collect();
/// let r = |x: &[f64], _seed: u64, out: &mut [f64]| {
///     for i in 0..n {
///         out[i] = (x[i] - target[i]).clamp(-0.2, 0.2);
///     }
/// };
/// let pattern = Sparsity::from_fn(n, n, |i, row| row.push(i))?;
/// let best = LeastSquares::new(pattern).budget(400).sigma0(0.3).seed(1).run(r, &vec![0.5; n])?;
/// assert!(best.fun < 1e-6 * n as f64, "{}", best.fun);
/// assert!(best.nfev <= 400);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LeastSquares {
    sparsity: Sparsity,
    budget: usize,
    sigma0: f64,
    pairs: usize,
    memory: usize,
    damping: f64,
    acceptance: Acceptance,
    max_rejections: usize,
    cg_iterations: usize,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float_box"))]
    bounds: Option<(Vec<f64>, Vec<f64>)>,
    seed: u64,
    smoothed_residuals: bool,
    max_step: f64,
    on_failure: FailurePolicy,
}

impl LeastSquares {
    /// The method on the pattern `sparsity` (its outputs and parameters fix `m` and `n`),
    /// with the defaults: budget 1000 evaluations, sigma0 0.1, 8 pairs, memory 8, damping
    /// 1e-3, steps of at most one sigma per coordinate, [`Acceptance::Descent`] with 3 rejections, 100 conjugate-gradient steps, no
    /// bounds, seed 0.
    pub fn new(sparsity: Sparsity) -> Self {
        LeastSquares {
            sparsity,
            budget: 1000,
            sigma0: 0.1,
            pairs: 8,
            memory: 8,
            damping: 1e-3,
            acceptance: Acceptance::Descent,
            max_rejections: 3,
            cg_iterations: 100,
            bounds: None,
            seed: 0,
            smoothed_residuals: false,
            max_step: 1.0,
            on_failure: FailurePolicy::Continue,
        }
    }

    /// The most evaluations of `r` (the start's included).
    pub fn budget(mut self, budget: usize) -> Self {
        self.budget = budget;
        self
    }

    /// The initial spread of the smoothing, in parameter units.
    pub fn sigma0(mut self, sigma0: f64) -> Self {
        self.sigma0 = sigma0;
        self
    }

    /// Antithetic pairs per Jacobian estimate.
    pub fn pairs(mut self, pairs: usize) -> Self {
        self.pairs = pairs;
        self
    }

    /// How many estimates the Jacobian averages (1: each iteration's alone).
    pub fn memory(mut self, memory: usize) -> Self {
        self.memory = memory;
        self
    }

    /// The initial Levenberg-Marquardt damping `lambda`.
    pub fn damping(mut self, damping: f64) -> Self {
        self.damping = damping;
        self
    }

    /// When a step is taken.
    pub fn acceptance(mut self, acceptance: Acceptance) -> Self {
        self.acceptance = acceptance;
        self
    }

    /// Refused steps in a row before the Jacobian is estimated again.
    pub fn max_rejections(mut self, max_rejections: usize) -> Self {
        self.max_rejections = max_rejections;
        self
    }

    /// Conjugate-gradient steps per solve.
    pub fn cg_iterations(mut self, cg_iterations: usize) -> Self {
        self.cg_iterations = cg_iterations;
        self
    }

    /// A box: every evaluated point is clamped onto it, and the start must lie inside.
    pub fn bounds(mut self, lower: Vec<f64>, upper: Vec<f64>) -> Self {
        self.bounds = Some((lower, upper));
        self
    }

    /// Which residuals the step solves for: `false` (the default), those of the current
    /// point, evaluated once and free of sampling noise under common random numbers;
    /// `true`, the smoothed residuals `E r(theta + tau)` estimated from the pairs (the exact
    /// Gauss-Newton step of the smoothed problem, but with the pairs' noise, which sets a
    /// floor on the sum of squares of about `m` times that noise's variance).
    pub fn smoothed_residuals(mut self, smoothed: bool) -> Self {
        self.smoothed_residuals = smoothed;
        self
    }

    /// The largest move of a coordinate in one step, in units of the current `sigma` (a box
    /// trust region: the smoothed Jacobian describes the residuals over about `sigma`
    /// around theta, not beyond); infinite: no limit.
    pub fn max_step(mut self, max_step: f64) -> Self {
        self.max_step = max_step;
        self
    }

    /// The seed of every draw (and of the seeds handed to `r`).
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// What the run does with a point whose outputs are not all finite (default
    /// [`FailurePolicy::Continue`]: a failed pair is left out of its Jacobian estimate, a
    /// failed step is refused and tried again shorter, and the failures are counted in
    /// [`VectorMinimum::failures`]; [`FailurePolicy::Raise`]: the run ends with
    /// [`Error::NonFiniteValue`]).
    pub fn on_failure(mut self, policy: FailurePolicy) -> Self {
        self.on_failure = policy;
        self
    }

    /// Every option's rule, and `x0` against the pattern and the box.
    fn validate(&self, x0: &[f64]) -> Result<(), Error> {
        check::theta(x0)?;
        check::len("x0", x0.len(), self.sparsity.params())?;
        check::at_least_one("budget", self.budget)?;
        check::positive("sigma0", self.sigma0)?;
        check::at_least_one("pairs", self.pairs)?;
        check::at_least_one("memory", self.memory)?;
        check::at_least_one("cg_iterations", self.cg_iterations)?;
        if self.max_step.is_nan() || self.max_step <= 0.0 {
            return Err(Error::InvalidParameter {
                name: "max_step",
                value: self.max_step.into(),
                reason: "must be > 0 (infinite: no limit)",
            });
        }
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "damping",
                value: self.damping.into(),
                reason: "must be finite and >= 0",
            });
        }
        if let Some((lo, hi)) = &self.bounds {
            check::len("lower bounds", lo.len(), x0.len())?;
            check::bounds(lo, hi)?;
            check::inside("x0", x0, lo, hi)?;
        }
        Ok(())
    }

    /// The run as ask and tell, from `x0`.
    ///
    /// # Errors
    /// An option out of its range, `x0` empty, not finite, of another length than the
    /// pattern's parameters, or outside the box.
    pub fn ask_tell(&self, x0: &[f64]) -> Result<LeastSquaresAskTell, Error> {
        self.validate(x0)?;
        let sigma_min = PAPER_SIGMA_MIN.min(self.sigma0);
        let annealer = Annealer::new(
            crate::anneal::Schedule::WarmLinear {
                warmup: crate::anneal::PAPER_WARMUP,
            },
            self.sigma0,
            sigma_min,
            self.budget,
        )?;
        Ok(LeastSquaresAskTell::new(self.clone(), annealer, x0))
    }

    /// Runs the method on `r(x, seed, out)`, which writes the `m` outputs at `x` into `out`
    /// (a slice reused from call to call: no allocation per evaluation).
    ///
    /// # Errors
    /// As [`LeastSquares::ask_tell`]; a non-finite output under [`FailurePolicy::Raise`]
    /// ([`Error::NonFiniteValue`]).
    pub fn run<F>(&self, mut r: F, x0: &[f64]) -> Result<VectorMinimum, Error>
    where
        F: FnMut(&[f64], u64, &mut [f64]),
    {
        let mut run = self.ask_tell(x0)?;
        let m = self.sparsity.outputs();
        let mut outputs = Vec::new();
        while let Some(ask) = run.ask()? {
            outputs.resize(ask.len() * m, 0.0);
            for ((x, seed), out) in ask.iter().zip(outputs.chunks_exact_mut(m)) {
                r(x, seed, out);
            }
            run.tell(&outputs)?;
        }
        run.finish()
    }

    /// [`LeastSquares::run`] for a closure that returns its outputs.
    ///
    /// ```
    /// use plateau_free::{LeastSquares, vector::Sparsity};
    /// let r = |x: &[f64]| vec![x[0] - 1.0, 2.0 * (x[1] + 0.5)];
    /// let options = LeastSquares::new(Sparsity::dense(2, 2)?).budget(200).sigma0(0.5);
    /// let best = options.run_vec(r, &[0.0, 0.0])?;
    /// assert!((best.x[0] - 1.0).abs() < 1e-3 && (best.x[1] + 0.5).abs() < 1e-3);
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`LeastSquares::run`]; a vector of the wrong length ([`Error::LengthMismatch`]).
    pub fn run_vec<F>(&self, r: F, x0: &[f64]) -> Result<VectorMinimum, Error>
    where
        F: Fn(&[f64]) -> Vec<f64>,
    {
        let mut run = self.ask_tell(x0)?;
        let m = self.sparsity.outputs();
        let mut outputs = Vec::new();
        while let Some(ask) = run.ask()? {
            outputs.clear();
            for (x, _) in ask.iter() {
                let out = r(x);
                check::len("outputs", out.len(), m)?;
                outputs.extend_from_slice(&out);
            }
            run.tell(&outputs)?;
        }
        run.finish()
    }
}

/// What the next ask evaluates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
enum Phase {
    /// The start.
    Start,
    /// The pairs of a Jacobian estimate around theta.
    Pairs,
    /// A step's point.
    Step,
    /// Nothing more: the budget is spent.
    Done,
}

/// A [`LeastSquares`] run as ask and tell: [`LeastSquaresAskTell::ask`] gives points (rows
/// of `n`) and their seeds, [`LeastSquaresAskTell::tell`] takes their outputs (rows of `m`,
/// in the points' order, flat). [`LeastSquares::run`] is written on it: the same options and
/// seed give the same bits.
///
/// ```
/// use plateau_free::{LeastSquares, vector::Sparsity};
/// let r = |x: &[f64]| vec![x[0] - 1.0, x[1] + 2.0];
/// let options = LeastSquares::new(Sparsity::dense(2, 2)?).budget(100).seed(3);
/// let mut run = options.ask_tell(&[0.0, 0.0])?;
/// while let Some(ask) = run.ask()? {
///     let outputs: Vec<f64> = ask.iter().flat_map(|(x, _seed)| r(x)).collect();
///     run.tell(&outputs)?;
/// }
/// let best = run.finish()?;
/// assert_eq!(best, options.run_vec(r, &[0.0, 0.0])?);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LeastSquaresAskTell {
    opts: LeastSquares,
    annealer: Annealer,
    phase: Phase,
    pending: bool,
    theta: Vec<f64>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    fun: f64,
    residuals: Vec<f64>,
    /// The averaged Jacobian, on the pattern's entries, and how many estimates it holds.
    jac: Vec<f64>,
    jac_count: usize,
    smoothed: Vec<f64>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    lambda: f64,
    rejections: usize,
    /// The ask's points, seeds and (for pairs) perturbations, flat.
    points: Vec<f64>,
    seeds: Vec<u64>,
    taus: Vec<f64>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    sigma: f64,
    nfev: usize,
    nit: usize,
    jacobians: usize,
    failures: usize,
}

impl LeastSquaresAskTell {
    fn new(opts: LeastSquares, annealer: Annealer, x0: &[f64]) -> Self {
        let lambda = opts.damping;
        LeastSquaresAskTell {
            annealer,
            phase: Phase::Start,
            pending: false,
            theta: x0.to_vec(),
            fun: f64::INFINITY,
            residuals: Vec::new(),
            jac: vec![0.0; opts.sparsity.nnz()],
            jac_count: 0,
            smoothed: Vec::new(),
            lambda,
            rejections: 0,
            points: Vec::new(),
            seeds: Vec::new(),
            taus: Vec::new(),
            sigma: opts.sigma0,
            nfev: 0,
            nit: 0,
            jacobians: 0,
            failures: 0,
            opts,
        }
    }

    /// The seed of every step point (and the start): one for the run, so that step values
    /// compare under common random numbers.
    fn step_seed(&self) -> u64 {
        stream_seed(self.opts.seed, u64::MAX, 0)
    }

    /// The next points to evaluate, or `None` once the budget is spent. Both members of a
    /// pair share one seed; every step point (and the start) gets the run's one step seed.
    ///
    /// # Errors
    /// [`Error::AskPending`]: the last points still wait for their outputs.
    pub fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        if self.pending {
            return Err(Error::AskPending);
        }
        let left = self.opts.budget - self.nfev;
        let needed = match self.phase {
            Phase::Start | Phase::Step => 1,
            Phase::Pairs => 2 * self.opts.pairs,
            Phase::Done => return Ok(None),
        };
        if needed > left {
            self.phase = Phase::Done;
            return Ok(None);
        }
        match self.phase {
            Phase::Start => {
                self.points.clone_from(&self.theta);
                self.seeds = vec![self.step_seed()];
            }
            Phase::Pairs => self.draw_pairs(),
            // The step's point is already in `points`.
            Phase::Step => self.seeds = vec![self.step_seed()],
            Phase::Done => unreachable!("returned above"),
        }
        self.pending = true;
        let n = self.theta.len();
        Ok(Some(Ask::new(Points::new(&self.points, n), &self.seeds)))
    }

    /// Draws the pairs of the next Jacobian estimate around theta, at the annealed spread.
    fn draw_pairs(&mut self) {
        let (n, pairs) = (self.theta.len(), self.opts.pairs);
        self.sigma = self.annealer.sigma(self.nfev);
        let estimate = self.jacobians as u64;
        self.taus.resize(pairs * n, 0.0);
        self.points.resize(2 * pairs * n, 0.0);
        self.seeds.clear();
        for (k, tau) in self.taus.chunks_exact_mut(n).enumerate() {
            draw(self.opts.seed, estimate, k, self.sigma, tau);
            let s = pair_seed(self.opts.seed, estimate, k);
            self.seeds.extend([s, s]);
            let (plus, minus) = self.points[2 * k * n..2 * (k + 1) * n].split_at_mut(n);
            for j in 0..n {
                plus[j] = self.theta[j] + tau[j];
                minus[j] = self.theta[j] - tau[j];
            }
        }
        self.clamp_points();
    }

    /// Clamps every asked point onto the box, if any (the estimate is then that of `r`
    /// composed with the projection).
    fn clamp_points(&mut self) {
        if let Some((lo, hi)) = &self.opts.bounds {
            let n = lo.len();
            for row in self.points.chunks_exact_mut(n) {
                for ((x, l), h) in row.iter_mut().zip(lo).zip(hi) {
                    *x = x.clamp(*l, *h);
                }
            }
        }
    }

    /// Takes the outputs of the asked points: rows of `m`, in the points' order, flat.
    ///
    /// # Errors
    /// [`Error::NothingAsked`]; [`Error::LengthMismatch`] for a count other than points x
    /// outputs; under [`FailurePolicy::Raise`], [`Error::NonFiniteValue`] naming the first
    /// non-finite output's point. After
    /// an error nothing has changed: the points still wait for their outputs.
    pub fn tell(&mut self, outputs: &[f64]) -> Result<(), Error> {
        if !self.pending {
            return Err(Error::NothingAsked);
        }
        let (n, m) = (self.theta.len(), self.opts.sparsity.outputs());
        let k = self.seeds.len();
        check::len("outputs (points x outputs)", outputs.len(), k * m)?;
        let points = &self.points;
        if self.opts.on_failure == FailurePolicy::Raise {
            check_outputs(
                outputs,
                m,
                |p| points[p * n..(p + 1) * n].to_vec(),
                self.nfev,
            )?;
        }
        self.pending = false;
        self.nfev += k;
        self.failures += outputs.chunks_exact(m).filter(|r| failed(r)).count();
        match self.phase {
            Phase::Start => {
                self.fun = if failed(outputs) {
                    f64::INFINITY
                } else {
                    sum_of_squares(outputs)
                };
                self.residuals = outputs.to_vec();
                self.phase = Phase::Pairs;
            }
            Phase::Pairs => {
                self.estimate(outputs);
                // With no pair's estimate yet (every pair failed), new pairs are drawn.
                if self.jac_count > 0 {
                    self.propose();
                }
            }
            Phase::Step => self.judge(outputs),
            Phase::Done => unreachable!("nothing is asked once done"),
        }
        Ok(())
    }

    /// The Jacobian estimate of the told pairs, averaged into the memory, and the smoothed
    /// residuals.
    fn estimate(&mut self, outputs: &[f64]) {
        let (n, m) = (self.theta.len(), self.opts.sparsity.outputs());
        let sp = &self.opts.sparsity;
        let mut acc = Accumulator::new(sp, false);
        for (k, tau) in self.taus.chunks_exact(n).enumerate() {
            let plus = &outputs[2 * k * m..(2 * k + 1) * m];
            let minus = &outputs[(2 * k + 1) * m..(2 * k + 2) * m];
            // A pair with a failed point says nothing about the slope: it is left out.
            if !failed(plus) && !failed(minus) {
                acc.add(sp, tau, self.sigma, plus, minus);
            }
        }
        self.jacobians += 1;
        self.rejections = 0;
        if acc.pairs == 0 {
            return;
        }
        let fresh = acc.finish();
        self.jac_count = (self.jac_count + 1).min(self.opts.memory);
        let w = 1.0 / self.jac_count as f64;
        for (j, f) in self.jac.iter_mut().zip(&fresh.values) {
            *j += w * (f - *j);
        }
        self.smoothed = fresh.residuals;
    }

    /// Solves for the damped step from theta and writes its point (clamped) as the next ask.
    fn propose(&mut self) {
        // A failed current point (the start) has no residuals of its own.
        let residuals = if self.opts.smoothed_residuals || !self.fun.is_finite() {
            &self.smoothed
        } else {
            &self.residuals
        };
        let d = damped_step(
            &self.opts.sparsity,
            &self.jac,
            residuals,
            self.lambda,
            self.opts.cg_iterations,
        );
        let limit = self.opts.max_step * self.sigma;
        self.points.clear();
        self.points.extend(
            self.theta
                .iter()
                .zip(&d)
                .map(|(x, s)| x + s.clamp(-limit, limit)),
        );
        self.clamp_points();
        self.phase = Phase::Step;
    }

    /// Takes or refuses the step whose outputs were told.
    fn judge(&mut self, outputs: &[f64]) {
        let fun = sum_of_squares(outputs);
        let taken = fun <= self.fun || self.opts.acceptance == Acceptance::Always;
        // A failed step's point is never taken.
        if taken && !failed(outputs) {
            std::mem::swap(&mut self.theta, &mut self.points);
            self.fun = fun;
            self.residuals = outputs.to_vec();
            self.lambda /= 3.0;
            self.nit += 1;
            self.phase = Phase::Pairs;
            return;
        }
        self.lambda = if self.lambda > 0.0 {
            self.lambda * 4.0
        } else {
            1e-3
        };
        self.rejections += 1;
        if self.rejections >= self.opts.max_rejections {
            self.phase = Phase::Pairs;
        } else {
            self.propose();
        }
    }

    /// Evaluations told so far.
    pub fn evaluations(&self) -> usize {
        self.nfev
    }

    /// The most evaluations the run spends ([`LeastSquares::budget`]); the driver's
    /// progress line shows the evaluations against it.
    ///
    /// ```
    /// use plateau_free::lifecycle::AskAndTell;
    /// use plateau_free::{LeastSquares, vector::Sparsity};
    /// let run = LeastSquares::new(Sparsity::dense(1, 1)?).budget(50).ask_tell(&[0.0])?;
    /// assert_eq!((run.budget(), AskAndTell::budget(&run)), (50, Some(50)));
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    pub fn budget(&self) -> usize {
        self.opts.budget
    }

    /// Evaluations told whose outputs were not all finite.
    pub fn failures(&self) -> usize {
        self.failures
    }

    /// The current point (the last step taken).
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// The current point's sum of squares (infinite before the start is told).
    pub fn fun(&self) -> f64 {
        self.fun
    }

    /// The spread of the last Jacobian estimate.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The averaged smoothed Jacobian, on the pattern's entries.
    pub fn jacobian(&self) -> &[f64] {
        &self.jac
    }

    /// The result, once [`LeastSquaresAskTell::ask`] has returned `None`.
    ///
    /// # Errors
    /// [`Error::Unfinished`] before that.
    pub fn finish(&self) -> Result<VectorMinimum, Error> {
        if self.phase != Phase::Done || self.pending {
            return Err(Error::Unfinished {
                evaluations: self.nfev,
                budget: self.opts.budget,
            });
        }
        Ok(self.result())
    }

    /// The best point so far (with [`Acceptance::Always`], the current one).
    pub fn result(&self) -> VectorMinimum {
        VectorMinimum {
            x: self.theta.clone(),
            fun: self.fun,
            residuals: self.residuals.clone(),
            nit: self.nit,
            jacobians: self.jacobians,
            nfev: self.nfev,
            failures: self.failures,
        }
    }
}

/// Whether a point failed: one of its outputs is NaN or infinite.
fn failed(outputs: &[f64]) -> bool {
    outputs.iter().any(|v| !v.is_finite())
}

/// `sum_i r_i^2`.
fn sum_of_squares(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

impl LeastSquaresAskTell {
    /// The outputs of `r` told per point (the pattern's rows).
    pub fn outputs(&self) -> usize {
        self.opts.sparsity.outputs()
    }

    /// The options of the run.
    pub fn options(&self) -> &LeastSquares {
        &self.opts
    }

    /// A read-back run's vectors against its pattern's sizes.
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self) -> Result<(), Error> {
        let (m, n, len) = (
            self.outputs(),
            self.opts.sparsity.params(),
            crate::check::len,
        );
        len("theta", self.theta.len(), n)?;
        len("jacobian", self.jac.len(), self.opts.sparsity.nnz())?;
        len("points", self.points.len(), self.seeds.len() * n)?;
        len("residuals", self.residuals.len() % m.max(1), 0)
    }
}
