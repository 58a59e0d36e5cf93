//! The SHADOW task (move a hidden sphere so that its shadow lands right) with its renders on
//! the worker ranks: rank 0 runs the paper's loop, ranks 1 and above render.
//!
//! ```text
//! cargo build --release -p plateau-free-mpi --example shadow
//! mpirun -n 3 target/release/examples/shadow [--iterations N] [--scale S] [--samples N]
//!                                            [--spp N] [--seed N] [--wait spin|backoff]
//!                                            [--check]
//! ```
//!
//! The defaults are the task's (supplemental Table 1: N = 2, 400 iterations, 32 spp, the full
//! 256 x 192 image). `--scale` multiplies the resolution; `--samples` sets N (with N = 2 only
//! two workers have work). `--check` then runs the same optimisation sequentially on rank 0
//! with the path tracer's own loop (`pathtracer::run::optimize`, what `pathtracer optimize`
//! runs), prints its time, and exits with status 1 unless the final parameters are
//! identical bit for bit. `--wait` chooses how the ranks wait for messages
//! ([`plateau_free_mpi::Wait`]; `backoff` by default).
//!
//! The objective is `pathtracer::run::optimize`'s: the image MSE of a render at theta
//! against the reference, every render with the run's seed (`Crn::Fixed`, the default) or
//! the pair's seed (`Crn::Pair`). Every rank renders the reference once for itself.

use std::process::ExitCode;
use std::time::Instant;

use mpi::traits::Communicator;
use mpi::Threading;
use pathtracer::run::{self, Crn, Settings};
use pathtracer::tasks::{self, param_mse, Task};
use plateau_free::{objective::Seeded, PlateauFreeGradient};
use plateau_free_mpi::Wait;

/// The command line: the settings, and whether to check against the sequential run.
fn parse(task: &Task) -> Result<(Settings, bool, Wait), String> {
    let mut s = Settings::defaults(task);
    let mut check = false;
    let mut wait = Wait::Backoff;
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        if flag == "--check" {
            check = true;
            continue;
        }
        let value = args.next().ok_or(format!("{flag} needs a value"))?;
        let bad = || format!("{flag} {value}: not a valid number");
        match flag.as_str() {
            "--iterations" => s.iterations = value.parse().map_err(|_| bad())?,
            "--samples" => s.samples = value.parse().map_err(|_| bad())?,
            "--spp" => s.spp = value.parse().map_err(|_| bad())?,
            "--seed" => s.seed = value.parse().map_err(|_| bad())?,
            "--wait" if value == "spin" => wait = Wait::Spin,
            "--wait" if value == "backoff" => wait = Wait::Backoff,
            "--scale" => s.scale = Some(value.parse().map_err(|_| bad())?),
            _ => return Err(format!("unknown option {flag}")),
        }
    }
    if s.iterations == 0 || s.samples == 0 || s.spp == 0 {
        return Err("--iterations, --samples and --spp must be positive".into());
    }
    // The sequential check renders the image error only at its first and last iteration.
    s.eval_every = s.iterations;
    Ok((s, check, wait))
}

/// The image loss of `pathtracer::run::optimize`: the MSE of a render at theta against the
/// reference.
fn image_loss<'a>(
    task: &'a Task,
    s: &'a Settings,
    reference: &'a tasks::Image,
) -> impl Fn(&[f64], u64) -> f64 + 'a {
    move |theta: &[f64], pair_seed: u64| {
        let seed = match s.crn {
            Crn::Fixed => s.seed,
            Crn::Pair => pair_seed,
        };
        task.render(theta, seed, s.spp, s.view()).mse(reference)
    }
}

/// The paper's loop as `pathtracer::run::optimize` configures it, over `objective`; returns
/// the final parameters.
fn optimize<O: plateau_free::Objective>(
    task: &Task,
    s: &Settings,
    objective: O,
) -> pathtracer::report::Result<Vec<f64>> {
    let mut estimator = PlateauFreeGradient::new(objective)
        .samples(s.samples)
        .sampling(s.sampling)
        .antithetic(s.antithetic)
        .seed(s.seed);
    let start = task.start();
    let history = run::optimizer(task, s)?.minimize(&mut estimator, &start)?;
    Ok(history.last_theta().unwrap_or(&start).to_vec())
}

fn main() -> ExitCode {
    let task = tasks::by_name("shadow").expect("the SHADOW task");
    let (s, check, wait) = match parse(&task) {
        Ok(parsed) => parsed,
        Err(message) => {
            eprintln!("shadow: {message}");
            return ExitCode::from(2);
        }
    };
    // Funneled: the renderer uses rayon's threads, only the main thread calls MPI.
    let Some((universe, _)) = mpi::initialize_with_threading(Threading::Funneled) else {
        eprintln!("shadow: MPI was already initialised");
        return ExitCode::FAILURE;
    };
    let world = universe.world();
    let reference = task.render(&task.target(), s.seed, s.spp, s.view());
    let loss = image_loss(&task, &s, &reference);

    if world.rank() != plateau_free_mpi::ROOT {
        return match plateau_free_mpi::serve_with(&world, &Seeded(&loss), wait) {
            Ok(_) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("shadow: {e}");
                ExitCode::FAILURE
            }
        };
    }

    let remote = match plateau_free_mpi::MpiBatch::new(&world) {
        Ok(remote) => remote.wait(wait),
        Err(e) => {
            eprintln!("shadow: {e}");
            return ExitCode::FAILURE;
        }
    };
    let started = Instant::now();
    let result = optimize(&task, &s, &remote);
    let mpi_seconds = started.elapsed().as_secs_f64();
    remote.finish();
    let theta = match result {
        Ok(theta) => theta,
        Err(e) => {
            eprintln!("shadow: {e}");
            return ExitCode::FAILURE;
        }
    };
    let target = task.target();
    println!(
        "shadow over MPI: {} workers, N = {}, {} iterations, {} spp, scale {}",
        world.size() - 1,
        s.samples,
        s.iterations,
        s.spp,
        s.scale.unwrap_or(1.0)
    );
    println!(
        "param MSE {:.3e} (start {:.3e}), theta {theta:?}",
        param_mse(&theta, &target),
        param_mse(&task.start(), &target)
    );
    println!(
        "time {mpi_seconds:.3} s ({:.2} ms per iteration)",
        1e3 * mpi_seconds / s.iterations as f64
    );
    if !check {
        return ExitCode::SUCCESS;
    }

    let sequential = match run::optimize(&task, &s, None, false) {
        Ok(outcome) => outcome.summary,
        Err(e) => {
            eprintln!("shadow: the sequential run failed: {e}");
            return ExitCode::FAILURE;
        }
    };
    let expected = sequential.final_theta.unwrap_or_default();
    println!(
        "sequential (pathtracer::run::optimize): param MSE {:.3e}, time {:.3} s, speed-up {:.2}",
        sequential.param_mse,
        sequential.seconds_total,
        sequential.seconds_total / mpi_seconds
    );
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    if bits(&theta) == bits(&expected) {
        println!("identical to the sequential run: yes");
        ExitCode::SUCCESS
    } else {
        println!("identical to the sequential run: NO (sequential theta {expected:?})");
        ExitCode::FAILURE
    }
}
