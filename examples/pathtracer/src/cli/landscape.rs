//! `landscape <task>`: the loss along one coordinate, raw and Gaussian-smoothed, as CSV.

use super::{usage, values};
use crate::report::Result;
use crate::tasks::View;

/// The options of `landscape`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// The task: cup, shadow, occlusion, gi, sort, caustic or texture.
    #[arg(value_parser = values::task)]
    task: String,
    /// The coordinate to vary (0 to the task's parameter count - 1).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, value_parser = values::at_least(0usize))]
    coordinate: usize,
    /// The coordinate's first value.
    #[arg(long, allow_hyphen_values = true, value_parser = values::finite)]
    from: f64,
    /// The coordinate's last value (above --from).
    #[arg(long, allow_hyphen_values = true, value_parser = values::finite)]
    to: f64,
    /// Points from --from to --to, both included.
    #[arg(long, default_value_t = 101, allow_negative_numbers = true, value_parser = values::at_least(2usize))]
    steps: usize,
    /// Vary around the start instead of the target.
    #[arg(long)]
    around_start: bool,
    /// Spreads of the smoothed curves (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.25,0.5", allow_hyphen_values = true, value_parser = values::positive)]
    sigmas: Vec<f64>,
    /// Samples per pixel of every render [default: the task's].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1u32))]
    spp: Option<u32>,
    /// Seed of the renderer's noise (the same for every render).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, value_parser = values::at_least(0u64))]
    seed: u64,
}

/// Prints `theta,loss,smoothed_<sigma>...`: the image MSE against the reference (same seed)
/// at `steps` points from `from` to `to`, and the same smoothed by a Gaussian quadrature over
/// that grid.
pub(super) fn run(args: Args) -> Result<()> {
    let Args {
        task,
        coordinate,
        from,
        to,
        steps,
        around_start,
        sigmas,
        spp,
        seed,
    } = args;
    let task = super::find_task(&task)?;
    if coordinate >= task.dim() {
        return Err(usage(format!(
            "--coordinate {coordinate}: allowed: 0 to {} ({}'s parameters)",
            task.dim() - 1,
            task.name()
        )));
    }
    if from >= to {
        return Err(usage(format!(
            "--from {from} --to {to}: allowed: --from below --to"
        )));
    }
    let spp = spp.unwrap_or(task.defaults().spp);
    let view = View::default();
    let reference = task.render(&task.target(), seed, spp, view);
    let mut theta = if around_start {
        task.start()
    } else {
        task.target()
    };
    let xs: Vec<f64> = (0..steps)
        .map(|k| from + (to - from) * k as f64 / (steps - 1) as f64)
        .collect();
    let losses: Vec<f64> = xs
        .iter()
        .map(|&x| {
            theta[coordinate] = x;
            task.render(&theta, seed, spp, view).mse(&reference)
        })
        .collect();
    print!("theta,loss");
    for s in &sigmas {
        print!(",smoothed_{s}");
    }
    println!();
    for (i, (&x, &l)) in xs.iter().zip(&losses).enumerate() {
        print!("{x},{l:e}");
        for &s in &sigmas {
            // Gaussian quadrature over the grid, renormalised where the kernel leaves it.
            let (mut num, mut den) = (0.0, 0.0);
            for (j, &y) in xs.iter().enumerate() {
                let w = (-0.5 * ((y - xs[i]) / s).powi(2)).exp();
                num += w * losses[j];
                den += w;
            }
            print!(",{:e}", num / den);
        }
        println!();
    }
    Ok(())
}
