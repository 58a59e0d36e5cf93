//! `timings`: every task's median render time at its defaults, as a markdown table.

use super::{median_seconds, values, with_threads};
use crate::render;
use crate::report::Result;
use crate::tasks::{self, View};

/// The options of `timings`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Renders per task; the table shows the median.
    #[arg(long, default_value_t = 11, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    repeat: usize,
    /// Worker threads for rendering [default: all cores].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    threads: Option<usize>,
}

/// Prints the table: target parameters, seed 0, scene set-up excluded.
pub(super) fn run(args: Args) -> Result<()> {
    with_threads(args.threads, || {
        println!("| task | resolution | spp | depth | median render (s) |\n|---|---|---|---|---|");
        for task in tasks::all() {
            let scene = task.scene(&task.target(), View::default());
            let spp = task.defaults().spp;
            let settings = render::Settings::new(spp, 0, task.max_depth());
            let seconds = median_seconds(args.repeat, || {
                let _ = render::render(&scene, &settings);
            });
            let (w, h) = (scene.camera.width, scene.camera.height);
            println!(
                "| {} | {w}x{h} | {spp} | {} | {seconds:.4} |",
                task.name(),
                task.max_depth(),
            );
        }
        Ok(())
    })
}
