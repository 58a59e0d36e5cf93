//! Measures what distribution over MPI buys: the time of one estimate against the number of
//! workers, for an objective of known cost (a sleep, which isolates the communication) and
//! for the real SHADOW render; and the overhead per estimate with an objective that costs
//! nothing, for 2, 1e3 and 1e5 parameters. Prints markdown tables (docs/scale-out.md).
//!
//! ```text
//! cargo build --release -p plateau-free-mpi --example scaling
//! target/release/examples/scaling [--max-ranks R] [--reps K]   # defaults: 4, 5
//! ```
//!
//! Run it directly (not under mpirun): it launches `mpirun -n R --oversubscribe` of itself
//! for each row (R = workers + 1, up to `--max-ranks`, default 4), and the sequential
//! baselines as plain processes. Every process renders on one thread (`RAYON_NUM_THREADS=1`),
//! so that a worker is one core's worth of work; ranks beyond the machine's cores share
//! them (the output says how many cores there are).

use std::process::{Command, ExitCode};
use std::time::{Duration, Instant};

use mpi::traits::Communicator;
use pathtracer::tasks;
use plateau_free::{objective::Batch, objective::Points, objective::Seeded, Objective};
use plateau_free_mpi::Wait;

/// Points per estimate in the speed-up rows: divisible by 1, 2, 3, 4 and 6 workers.
const POINTS: usize = 12;
/// The sleeping objective's cost per evaluation.
const SLEEP_MS: u64 = 20;
/// The SHADOW render's resolution multiplier in the speed-up rows (64 x 48 pixels, 32 spp).
const SHADOW_SCALE: f64 = 0.25;
/// Points per estimate in the overhead rows (the paper's loop uses 2 to 32).
const OVERHEAD_POINTS: usize = 8;

/// An objective the measurements use, by name: `sleep`, `shadow` or `zero`.
fn objective(kind: &str) -> Box<dyn Objective> {
    match kind {
        "sleep" => Box::new(|x: &[f64]| {
            std::thread::sleep(Duration::from_millis(SLEEP_MS));
            x[0]
        }),
        "shadow" => {
            let task = tasks::by_name("shadow").expect("the SHADOW task");
            let view = tasks::View {
                fov_degrees: None,
                scale: Some(SHADOW_SCALE),
            };
            let spp = task.defaults().spp;
            let reference = task.render(&task.target(), 0, spp, view);
            Box::new(Seeded(move |x: &[f64], seed: u64| {
                task.render(x, seed, spp, view).mse(&reference)
            }))
        }
        // Reads every coordinate, so that the points really arrive.
        _ => Box::new(Batch(|points: Points<'_>, _: &[u64], out: &mut [f64]| {
            for (p, o) in points.iter().zip(out.iter_mut()) {
                *o = p.iter().sum();
            }
        })),
    }
}

/// `len` points of dimension `dim` around the SHADOW start, and their seeds.
fn points(len: usize, dim: usize) -> (Vec<f64>, Vec<u64>) {
    let flat = (0..len * dim)
        .map(|i| 0.1 * (i % 7) as f64 - 0.3 + if i % dim == 1 { 2.0 } else { -0.5 })
        .collect();
    (flat, (0..len as u64).collect())
}

/// The median time of `reps` estimates (after one to warm up).
fn time_estimates(f: &dyn Objective, len: usize, dim: usize, reps: usize) -> f64 {
    let (flat, seeds) = points(len, dim);
    let mut out = vec![0.0; len];
    f.evaluate_batch(Points::new(&flat, dim), &seeds, &mut out);
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            f.evaluate_batch(Points::new(&flat, dim), &seeds, &mut out);
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[reps / 2]
}

/// One measurement in this process or, under mpirun, over the job: prints `seconds S`.
fn child(
    kind: &str,
    len: usize,
    dim: usize,
    reps: usize,
    sequential: bool,
    wait: Wait,
) -> ExitCode {
    let f = objective(kind);
    if sequential {
        println!("seconds {}", time_estimates(&*f, len, dim, reps));
        return ExitCode::SUCCESS;
    }
    let Some(universe) = mpi::initialize() else {
        return ExitCode::FAILURE;
    };
    let world = universe.world();
    if world.rank() != plateau_free_mpi::ROOT {
        return match plateau_free_mpi::serve_with(&world, &*f, wait) {
            Ok(_) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("scaling: {e}");
                ExitCode::FAILURE
            }
        };
    }
    let code = match plateau_free_mpi::MpiBatch::new(&world) {
        Ok(remote) => {
            let remote = remote.wait(wait);
            println!("seconds {}", time_estimates(&remote, len, dim, reps));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("scaling: {e}");
            ExitCode::FAILURE
        }
    };
    code
}

/// Runs this program as a child (`ranks == 0`: a plain process) and returns its `seconds`.
fn measure(
    kind: &str,
    (len, dim): (usize, usize),
    reps: usize,
    ranks: usize,
    wait: Wait,
) -> Result<f64, String> {
    let me = std::env::current_exe().map_err(|e| e.to_string())?;
    let args = [
        "--child".to_string(),
        kind.into(),
        len.to_string(),
        dim.to_string(),
        reps.to_string(),
    ];
    let mut command = if ranks == 0 {
        let mut c = Command::new(&me);
        c.args(&args).arg("--sequential");
        c
    } else {
        let mut c = Command::new("mpirun");
        c.args(["-n", &ranks.to_string(), "--oversubscribe"])
            .arg(&me)
            .args(&args);
        if wait == Wait::Spin {
            c.arg("--spin");
        }
        c
    };
    let out = command
        .env("RAYON_NUM_THREADS", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .output()
        .map_err(|e| {
            format!("cannot start {command:?} (scripts/install-mpi installs mpirun): {e}")
        })?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    stdout
        .lines()
        .find_map(|line| line.strip_prefix("seconds "))
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| {
            format!(
                "{command:?} printed no time:\n{stdout}\n{}",
                String::from_utf8_lossy(&out.stderr)
            )
        })
}

fn driver(max_ranks: usize, reps: usize) -> Result<(), String> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "{cores} cores; every process on one thread; ranks = workers + 1 (rank 0 only optimises)\n"
    );
    println!(
        "| objective | workers | ms per estimate of {POINTS} points | speed-up | efficiency |"
    );
    println!("|---|---|---|---|---|");
    for (kind, label) in [
        ("sleep", format!("sleep {SLEEP_MS} ms")),
        ("shadow", format!("SHADOW render, scale {SHADOW_SCALE}")),
    ] {
        let sequential = measure(kind, (POINTS, 2), reps, 0, Wait::Backoff)?;
        println!("| {label} | sequential | {:.1} | 1 | |", 1e3 * sequential);
        for ranks in 2..=max_ranks {
            let workers = ranks - 1;
            let t = measure(kind, (POINTS, 2), reps, ranks, Wait::Backoff)?;
            let speedup = sequential / t;
            println!(
                "| {label} | {workers}{} | {:.1} | {speedup:.2} | {:.0}% |",
                if ranks > cores {
                    format!(" ({ranks} ranks on {cores} cores)")
                } else {
                    String::new()
                },
                1e3 * t,
                100.0 * speedup / workers as f64
            );
        }
    }
    println!("\n| parameters n | MB per estimate ({OVERHEAD_POINTS} points, both ways) | workers | ms per estimate, zero-cost objective, Wait::Backoff | the same, Wait::Spin | local, ms |");
    println!("|---|---|---|---|---|---|");
    for dim in [2, 1_000, 100_000] {
        let local = measure("zero", (OVERHEAD_POINTS, dim), reps * 10, 0, Wait::Backoff)?;
        let megabytes = (OVERHEAD_POINTS * (dim + 3) * 8) as f64 / 1e6;
        for ranks in 2..=max_ranks.min(3) {
            let backoff = measure(
                "zero",
                (OVERHEAD_POINTS, dim),
                reps * 10,
                ranks,
                Wait::Backoff,
            )?;
            let spin = measure("zero", (OVERHEAD_POINTS, dim), reps * 10, ranks, Wait::Spin)?;
            println!(
                "| {dim} | {megabytes:.3} | {} | {:.3} | {:.3} | {:.3} |",
                ranks - 1,
                1e3 * backoff,
                1e3 * spin,
                1e3 * local
            );
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--child") {
        let number = |i: usize| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(1);
        let kind = args.get(1).map_or("zero", String::as_str);
        let sequential = args.iter().any(|a| a == "--sequential");
        let wait = if args.iter().any(|a| a == "--spin") {
            Wait::Spin
        } else {
            Wait::Backoff
        };
        return child(kind, number(2), number(3), number(4), sequential, wait);
    }
    let (mut max_ranks, mut reps) = (4, 5);
    let mut rest = args.iter();
    while let Some(flag) = rest.next() {
        let value = rest.next().and_then(|v| v.parse::<usize>().ok());
        match (flag.as_str(), value) {
            ("--max-ranks", Some(v)) if v >= 2 => max_ranks = v,
            ("--reps", Some(v)) if v >= 1 => reps = v,
            _ => {
                eprintln!("usage: scaling [--max-ranks R >= 2] [--reps K >= 1]");
                return ExitCode::from(2);
            }
        }
    }
    match driver(max_ranks, reps) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("scaling: {e}");
            ExitCode::FAILURE
        }
    }
}
