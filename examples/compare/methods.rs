//! The methods compared, each run on a problem through a [`Recorder`] that counts the
//! evaluations and notes when each target is first reached.

use std::cell::{Cell, RefCell};

use plateau_free::{Adam, Annealer, Optimizer, PlateauFreeGradient};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::functions::Problem;
use crate::TARGETS;

/// Counts evaluations and records when each target is first reached.
pub(crate) struct Recorder<'a> {
    pub(crate) problem: &'a Problem,
    pub(crate) budget: usize,
    pub(crate) evals: Cell<usize>,
    pub(crate) best: Cell<f64>,
    pub(crate) hits: RefCell<[Option<usize>; 11]>,
}

impl<'a> Recorder<'a> {
    /// A record of `problem` that counts the first `budget` evaluations.
    pub(crate) fn new(problem: &'a Problem, budget: usize) -> Self {
        Recorder {
            problem,
            budget,
            evals: Cell::new(0),
            best: Cell::new(f64::INFINITY),
            hits: RefCell::new([None; 11]),
        }
    }

    /// The value at `x`, counted, with the targets it reaches noted.
    pub(crate) fn eval(&self, x: &[f64]) -> f64 {
        let v = self.problem.eval(x);
        let e = self.evals.get() + 1;
        self.evals.set(e);
        if e <= self.budget && v < self.best.get() {
            self.best.set(v);
            let mut hits = self.hits.borrow_mut();
            for (t, h) in TARGETS.iter().zip(hits.iter_mut()) {
                if h.is_none() && v <= *t {
                    *h = Some(e);
                }
            }
        }
        v
    }
}

/// A method compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Method {
    /// `plateau_free::minimize`, the library's default.
    Minimize,
    /// The paper's loop: the plateau-free gradient, Adam and the annealer.
    Paper,
    /// CMA-ES (the `cmaes` crate).
    Cmaes,
    /// CMA-ES with IPOP restarts.
    CmaesIpop,
    /// Uniform random search in [-5, 5]^n, after x0.
    Random,
    /// Trust-region Newton steps on the smoothed objective (`newton.rs`).
    SmoothedNewton,
}

impl Method {
    /// Every method, in the page's order.
    pub(crate) const ALL: [Method; 6] = [
        Method::Minimize,
        Method::Cmaes,
        Method::CmaesIpop,
        Method::Random,
        Method::Paper,
        Method::SmoothedNewton,
    ];

    /// The method's name on the command line and the page.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Method::Minimize => "minimize",
            Method::Paper => "paper-loop",
            Method::Cmaes => "cmaes",
            Method::CmaesIpop => "cmaes-ipop",
            Method::Random => "random",
            Method::SmoothedNewton => "smoothed-newton",
        }
    }

    /// The method called `s`.
    pub(crate) fn parse(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }

    /// Runs the method with `seed` on the problem of `rec`, within its budget.
    pub(crate) fn run(self, rec: &Recorder<'_>, seed: u64) {
        let p = rec.problem;
        let n = p.n;
        let budget = rec.budget;
        let f = |x: &[f64]| rec.eval(x);
        match self {
            Method::Minimize => {
                // Stopping at 1e-8 only saves time: every target is reached there.
                let m = plateau_free::Minimizer::new(f)
                    .budget(budget)
                    .seed(seed)
                    .target(1e-8);
                let _ = crate::variant::variant(m).run(&p.x0);
            }
            Method::Paper => {
                // The README's settings, as a new user would try them: N = 4, lr 0.02,
                // Annealer::paper(0.5, iterations) with the iterations the budget allows.
                let mut grad = PlateauFreeGradient::new(f).samples(4).seed(seed);
                let iterations = budget / 4;
                let mut opt = Optimizer::new(
                    Adam::new(0.02).expect("valid lr"),
                    Annealer::paper(0.5, iterations).expect("valid schedule"),
                )
                .record_theta(false);
                // The loop evaluates f only at perturbed points; its final point counts too.
                if let Ok(h) = opt.minimize(&mut grad, &p.x0) {
                    if let Some(x) = h.last_theta() {
                        rec.eval(x);
                    }
                }
            }
            Method::Cmaes => {
                // One run from x0 with step size 2 (a fifth of the domain [-5, 5], as the
                // BBOB setups of CMA-ES use), its default population and termination.
                let opts = cmaes::CMAESOptions::new(p.x0.clone(), 2.0)
                    .max_function_evals(budget)
                    .fun_target(1e-8)
                    .seed(seed);
                if let Ok(mut state) = opts.build(|x: &cmaes::DVector<f64>| rec.eval(x.as_slice()))
                {
                    state.run();
                }
            }
            Method::CmaesIpop => {
                // The crate's IPOP restarts (population doubled at each restart; each run
                // starts at a uniform point of [-5, 5]^n).
                use cmaes::restart::{RestartOptions, RestartStrategy, IPOP};
                let strategy = RestartStrategy::IPOP(IPOP::new(2).expect("valid factor"));
                if let Ok(r) = RestartOptions::new(n, -5.0..=5.0, strategy)
                    .max_function_evals(budget)
                    .fun_target(1e-8)
                    .seed(seed)
                    .build()
                {
                    r.run(|| |x: &cmaes::DVector<f64>| rec.eval(x.as_slice()));
                }
            }
            Method::SmoothedNewton => crate::newton::run(f, &p.x0, budget, seed),
            Method::Random => {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xA5A5);
                f(&p.x0);
                let mut x = vec![0.0; n];
                for _ in 1..budget {
                    x.iter_mut().for_each(|v| *v = rng.random_range(-5.0..5.0));
                    f(&x);
                }
            }
        }
    }
}
