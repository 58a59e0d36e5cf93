//! `landscape <task>`: the loss along one coordinate, raw and Gaussian-smoothed, as CSV.

use crate::report::Result;
use crate::tasks::View;

/// The options of `landscape`.
#[derive(clap::Args)]
pub(super) struct Args {
    task: String,
    /// The coordinate to vary.
    #[arg(long, default_value_t = 0)]
    coordinate: usize,
    #[arg(long, allow_hyphen_values = true)]
    from: f64,
    #[arg(long, allow_hyphen_values = true)]
    to: f64,
    #[arg(long, default_value_t = 101)]
    steps: usize,
    /// Vary around the start instead of the target.
    #[arg(long)]
    around_start: bool,
    /// Spreads of the smoothed curves (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.25,0.5")]
    sigmas: Vec<f64>,
    #[arg(long)]
    spp: Option<u32>,
    #[arg(long, default_value_t = 0)]
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
    if coordinate >= task.dim() || steps < 2 || from.is_nan() || to.is_nan() || from >= to {
        return Err("need coordinate < dim, steps >= 2 and from < to".into());
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
