//! Path-tracing examples of plateau: the paper's seven inverse-rendering tasks.
//!
//! `render` draws one task at given parameters; the optimisation front-ends come later.

// The renderer and the tasks are this example's internal library: each front-end (render,
// optimize, the benches, the tests) uses a different part of their public surface.
#[allow(dead_code)]
mod render;
#[allow(dead_code)]
mod tasks;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};

use tasks::View;

#[derive(Parser)]
#[command(about = "Inverse path tracing with plateau-free gradients")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render one task at its start, its target (default) or given parameters.
    Render {
        /// cup, shadow, occlusion, gi, sort, caustic or texture.
        task: String,
        /// Render at the optimisation's start.
        #[arg(long, conflicts_with_all = ["target", "params"])]
        initial: bool,
        /// Render at the target (the default).
        #[arg(long, conflicts_with = "params")]
        target: bool,
        /// Comma-separated parameters.
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        params: Option<Vec<f64>>,
        /// Samples per pixel (default: the task's).
        #[arg(long)]
        spp: Option<u32>,
        /// Random seed of the render.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Resolution multiplier.
        #[arg(long)]
        scale: Option<f64>,
        /// Horizontal field of view in degrees (default: the task's).
        #[arg(long)]
        fov: Option<f64>,
        /// Render this many times and report the median time (the image is the last one).
        #[arg(long, default_value_t = 1)]
        repeat: usize,
        /// Output image, .png (sRGB) or .exr (linear).
        #[arg(long)]
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    match Cli::parse().command {
        Command::Render {
            task,
            initial,
            target: _,
            params,
            spp,
            seed,
            scale,
            fov,
            repeat,
            out,
        } => {
            let Some(task) = tasks::by_name(&task) else {
                eprintln!("unknown task {task:?}");
                return ExitCode::FAILURE;
            };
            let theta = match params {
                Some(p) if p.len() != task.dim() => {
                    eprintln!(
                        "{} takes {} parameters, got {}",
                        task.name(),
                        task.dim(),
                        p.len()
                    );
                    return ExitCode::FAILURE;
                }
                Some(p) => p,
                None if initial => task.start(),
                None => task.target(),
            };
            let view = View {
                fov_degrees: fov,
                scale,
            };
            let spp = spp.unwrap_or(task.defaults().spp);
            let mut times = Vec::new();
            let mut image = None;
            for _ in 0..repeat.max(1) {
                let t0 = Instant::now();
                image = Some(task.render(&theta, seed, spp, view));
                times.push(t0.elapsed().as_secs_f64());
            }
            times.sort_by(f64::total_cmp);
            println!("render_seconds: {:.6}", times[times.len() / 2]);
            if let Some(image) = image {
                if let Err(e) = image.save(&out) {
                    eprintln!("{e}");
                    return ExitCode::FAILURE;
                }
            }
            ExitCode::SUCCESS
        }
    }
}
