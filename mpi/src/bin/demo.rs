//! `plateau-free-mpi-demo`: seeded test functions optimised over MPI, with the results printed as
//! bit patterns so that a run under `mpirun` can be compared with the sequential one exactly
//! (`tests/mpirun.rs` does).
//!
//! ```text
//! plateau-free-mpi-demo MODE [--sequential] [--spin] [--dim N] [--samples N] [--iterations N]
//!   MODE  paper         the paper's loop (plateau-free gradient, Adam, annealing)
//!         minimize      plateau_free::Minimizer (the adaptive search)
//!         values        one batch whose values are NaN, infinities, -0.0, subnormal
//!         panic         an objective that panics: rank 0 panics with the worker's message
//!         panic-caught  the same under catch_panics: rank 0 reports the error and ends well
//!   --sequential  evaluate in this process, without MPI (the reference)
//!   --spin        wait for messages with MPI's blocking probe (plateau_free_mpi::Wait::Spin)
//! ```
//!
//! Under `mpirun`, rank 0 prints `theta`, `values` and `evaluations` lines (hex bit
//! patterns) and, on stderr, what each worker served. The workers send that report to rank 0
//! rather than print it: when rank 0 exits non-zero, mpirun kills the other ranks and can drop
//! output still on its way from them (CI saw a worker's line go missing that way).

use std::process::ExitCode;

use mpi::point_to_point::{Destination, Source};
use mpi::traits::Communicator;
use plateau_free::seeding::mix;
use plateau_free::{
    objective::Points, objective::Seeded, Adam, Annealer, Minimizer, Objective, Optimizer,
    PlateauFreeGradient,
};
use plateau_free_mpi::Wait;

/// The tag of a worker's report to rank 0, above the tags `plateau_free_mpi` uses.
const REPORT: mpi::Tag = 100;

/// The command line.
struct Args {
    mode: String,
    sequential: bool,
    wait: Wait,
    dim: usize,
    samples: usize,
    iterations: usize,
}

fn parse() -> Result<Args, String> {
    let mut args = std::env::args().skip(1);
    let mode = args.next().ok_or(
        "usage: plateau-free-mpi-demo MODE [--sequential] [--spin] [--dim N] [--samples N] [--iterations N]",
    )?;
    let mut parsed = Args {
        mode,
        sequential: false,
        wait: Wait::Backoff,
        dim: 6,
        samples: 8,
        iterations: 60,
    };
    while let Some(flag) = args.next() {
        if flag == "--sequential" {
            parsed.sequential = true;
            continue;
        }
        if flag == "--spin" {
            parsed.wait = Wait::Spin;
            continue;
        }
        let value = args.next().ok_or(format!("{flag} needs a value"))?;
        let number: usize = value
            .parse()
            .map_err(|_| format!("{flag} {value}: not a whole number"))?;
        match flag.as_str() {
            "--dim" if number > 0 => parsed.dim = number,
            "--samples" if number > 0 => parsed.samples = number,
            "--iterations" => parsed.iterations = number,
            _ => return Err(format!("{flag} {value}: unknown option or zero")),
        }
    }
    match parsed.mode.as_str() {
        "paper" | "minimize" | "values" | "panic" | "panic-caught" => Ok(parsed),
        other => Err(format!("unknown mode {other}")),
    }
}

/// A staircase with a plateau around the start and seeded noise: the squared distance of the
/// rounded point to an integer target, plus up to 1e-3 of noise drawn from the seed (so that
/// a seed sent to the wrong point changes the result).
fn staircase(x: &[f64], seed: u64) -> f64 {
    let distance: f64 = x
        .iter()
        .enumerate()
        .map(|(i, v)| (v.round() - (i % 3) as f64 + 1.0).powi(2))
        .sum();
    distance + 1e-3 * (mix(seed) >> 11) as f64 / (1u64 << 53) as f64
}

/// Values that must cross MPI unchanged, chosen by the point's first coordinate.
fn special(x: &[f64], _seed: u64) -> f64 {
    match x[0] as i64 {
        0 => f64::NAN,
        1 => f64::INFINITY,
        2 => f64::NEG_INFINITY,
        3 => -0.0,
        4 => f64::from_bits(0x7ff4_0000_dead_beef), // a NaN with a payload
        5 => f64::MIN_POSITIVE / 3.0,               // subnormal
        k => k as f64 * 0.1,
    }
}

/// A panicking objective.
fn panicking(_x: &[f64], _seed: u64) -> f64 {
    panic!("deliberate panic in the objective")
}

fn hex(values: &[f64]) -> String {
    values
        .iter()
        .map(|v| format!("{:016x}", v.to_bits()))
        .collect::<Vec<_>>()
        .join(",")
}

/// Runs the mode with `objective` (local or remote) and prints the result.
fn run<O: Objective>(args: &Args, objective: O) -> Result<(), plateau_free::Error> {
    let start: Vec<f64> = (0..args.dim).map(|i| 0.3 * i as f64 - 0.4).collect();
    match args.mode.as_str() {
        "paper" | "panic" | "panic-caught" => {
            let mut grad = PlateauFreeGradient::new(objective)
                .samples(args.samples)
                .seed(11)
                .catch_panics(args.mode == "panic-caught");
            let mut opt = Optimizer::new(Adam::new(0.05)?, Annealer::paper(0.6, args.iterations)?);
            let history = match opt.minimize(&mut grad, &start) {
                Err(e) if args.mode == "panic-caught" => {
                    println!("error {e}");
                    return Ok(());
                }
                other => other?,
            };
            println!("theta {}", hex(history.last_theta().unwrap_or(&start)));
            println!("values {}", hex(&history.value));
            println!("evaluations {}", history.evaluations);
        }
        "minimize" => {
            let best = Minimizer::new(objective)
                .budget(args.iterations * args.samples)
                .seed(5)
                .run(&start)?;
            println!("theta {}", hex(&best.x));
            println!("values {}", hex(&[best.fun, best.sigma]));
            println!("evaluations {} {}", best.evaluations, best.iterations);
        }
        _ => {
            let flat: Vec<f64> = (0..args.samples * args.dim)
                .map(|i| (i / args.dim) as f64 + 0.25)
                .collect();
            let seeds: Vec<u64> = (0..args.samples as u64).collect();
            let mut out = vec![0.0; args.samples];
            objective.evaluate_batch(Points::new(&flat, args.dim), &seeds, &mut out);
            println!("values {}", hex(&out));
        }
    }
    Ok(())
}

/// The objective of a mode.
fn objective_of(mode: &str) -> fn(&[f64], u64) -> f64 {
    match mode {
        "values" => special,
        "panic" | "panic-caught" => panicking,
        _ => staircase,
    }
}

fn main() -> ExitCode {
    let args = match parse() {
        Ok(args) => args,
        Err(message) => {
            eprintln!("plateau-free-mpi-demo: {message}");
            return ExitCode::from(2);
        }
    };
    let f = Seeded(objective_of(&args.mode));
    let outcome = if args.sequential {
        run(&args, f).map_err(|e| e.to_string())
    } else {
        let Some(universe) = mpi::initialize() else {
            eprintln!("plateau-free-mpi-demo: MPI was already initialised");
            return ExitCode::FAILURE;
        };
        let world = universe.world();
        if world.rank() == plateau_free_mpi::ROOT {
            // A worker's panic re-panics here ("panic" mode). It is caught so that rank 0
            // still reaches MPI's finalisation, which waits for the workers: were rank 0 to
            // die of the panic, mpirun could kill them before they report what they served.
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                plateau_free_mpi::MpiBatch::new(&world)
                    .map_err(|e| e.to_string())
                    .and_then(|remote| {
                        let remote = remote.wait(args.wait);
                        let result = run(&args, &remote).map_err(|e| e.to_string());
                        remote.finish();
                        result
                    })
            }))
            .unwrap_or_else(|_| Err("rank 0 panicked (message above)".into()));
            // Every worker has stopped serving by now (`finish`, or MpiBatch's Drop while
            // rank 0 unwound), so each sends its report next.
            for rank in 1..world.size() {
                let (report, _) = world
                    .process_at_rank(rank)
                    .receive_vec_with_tag::<u8>(REPORT);
                eprintln!("rank {rank}: {}", String::from_utf8_lossy(&report));
            }
            outcome
        } else {
            let served = plateau_free_mpi::serve_with(&world, &f, args.wait);
            let report = match &served {
                Ok(served) => format!("{served:?}"),
                Err(e) => format!("failed: {e}"),
            };
            let root = world.process_at_rank(plateau_free_mpi::ROOT);
            root.send_with_tag(report.as_bytes(), REPORT);
            served.map(|_| ()).map_err(|e| e.to_string())
        }
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("plateau-free-mpi-demo: {message}");
            ExitCode::FAILURE
        }
    }
}
