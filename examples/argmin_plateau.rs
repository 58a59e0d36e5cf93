//! argmin's steepest descent and L-BFGS on a staircase, flat almost everywhere, with the
//! plateau-free gradient (feature `argmin`).
//!
//! `cargo run --release --features argmin --example argmin_plateau`
//!
//! The loss is `floor(4 |x|^2) / 4` in 2-D: terraces around the minimum at the origin, whose
//! plain gradient is zero everywhere it exists. Both solvers start on a terrace.
use argmin::core::{Executor, OptimizationResult, State};
use argmin::solver::gradientdescent::SteepestDescent;
use argmin::solver::linesearch::{condition::ArmijoCondition, BacktrackingLineSearch};
use argmin::solver::quasinewton::LBFGS;
use plateau_free::argmin::{ArgminProblem, ArgminState, Spread};
use plateau_free::{Annealer, PlateauFreeGradient};

/// The loss as a plain function pointer, so that the problem's type can be named.
type Loss = fn(&[f64]) -> f64;

fn terraces(x: &[f64]) -> f64 {
    (4.0 * (x[0] * x[0] + x[1] * x[1])).floor() / 4.0
}

/// The problem: 16 evaluations per gradient, a spread annealed from 0.5 to 0.01 over
/// `iterations` gradient calls (one per iteration with a backtracking line search).
fn problem(iterations: usize) -> Result<ArgminProblem<Loss>, plateau_free::Error> {
    let estimator = PlateauFreeGradient::new(terraces as Loss)
        .samples(16)
        .seed(3);
    ArgminProblem::new(
        estimator,
        Spread::Annealed(Annealer::paper(0.5, iterations)?),
    )
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let start = vec![1.2, -0.9];
    let iterations = 60;
    println!("start {start:?}, loss {}", terraces(&start));

    // Armijo backtracking: it compares costs only (the smoothed loss, with common random
    // numbers), never the noisy gradient at trial points.
    // Halving from a unit step: a few costs per iteration (argmin's default 0.9 needs dozens).
    let line_search = BacktrackingLineSearch::new(ArmijoCondition::new(1e-4)?).rho(0.5)?;
    let run = Executor::new(problem(iterations)?, SteepestDescent::new(line_search))
        .configure(|s| s.param(start.clone()).max_iters(iterations as u64))
        .run()?;
    report("steepest descent", &run);

    let line_search = BacktrackingLineSearch::new(ArmijoCondition::new(1e-4)?).rho(0.5)?;
    let solver = LBFGS::new(line_search, 5).with_tolerance_grad(0.0)?;
    let run = Executor::new(problem(iterations)?, solver)
        .configure(|s| s.param(start.clone()).max_iters(iterations as u64))
        .run()?;
    report("L-BFGS", &run);
    overhead()
}

/// The adapter's cost over calling the estimator directly: the time per gradient of a cheap
/// `f` (16 evaluations of the terraces), best of 5 rounds of 20,000 calls each way.
fn overhead() -> Result<(), Box<dyn std::error::Error>> {
    use argmin::core::Gradient;
    use std::time::Instant;
    let (calls, theta) = (20_000, vec![0.3, -0.2]);
    let make = || PlateauFreeGradient::new(terraces as Loss).samples(16);
    let (mut direct_best, mut adapter_best) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..5 {
        let mut direct = make();
        let start = Instant::now();
        for _ in 0..calls {
            std::hint::black_box(direct.estimate(&theta, 0.3)?);
        }
        direct_best = direct_best.min(start.elapsed().as_secs_f64() / f64::from(calls));
        let adapter = ArgminProblem::new(make(), Spread::Fixed(0.3))?;
        let start = Instant::now();
        for _ in 0..calls {
            std::hint::black_box(adapter.gradient(&theta)?);
        }
        adapter_best = adapter_best.min(start.elapsed().as_secs_f64() / f64::from(calls));
    }
    println!(
        "overhead: direct estimate {:.0} ns, through argmin's Gradient {:.0} ns per call ({:+.0} ns)",
        direct_best * 1e9,
        adapter_best * 1e9,
        (adapter_best - direct_best) * 1e9
    );
    Ok(())
}

/// The run's best point, its loss, why it stopped and what it cost.
fn report<S, F>(name: &str, run: &OptimizationResult<ArgminProblem<F>, S, ArgminState>) {
    let state = run.state();
    let best = state
        .get_best_param()
        .expect("the run keeps its best point");
    let problem = run
        .problem
        .problem
        .as_ref()
        .expect("the executor keeps the problem");
    println!(
        "{name:17} best {best:.3?}  loss {}  after {} iterations ({:?}), {} gradients, {} costs",
        terraces(best),
        state.get_iter(),
        state.get_termination_reason(),
        problem.gradient_calls(),
        problem.cost_calls()
    );
}
