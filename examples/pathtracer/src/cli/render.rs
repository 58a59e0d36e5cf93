//! `render <task>`: one image at the target, the start or given parameters, and its time.

use std::path::PathBuf;

use super::point::Point;
use super::{values, with_threads, RenderOptions};
use crate::render;
use crate::report::Result;

/// The options of `render`.
#[derive(clap::Args)]
pub(super) struct Args {
    #[command(flatten)]
    point: Point,
    #[command(flatten)]
    render: RenderOptions,
    /// Render this many times and print the median time (the image is the last one).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    repeat: usize,
    /// The image to write: a .png (sRGB) or .exr (linear) file.
    #[arg(long, value_parser = values::image_file)]
    out: PathBuf,
}

/// Renders, prints `render_seconds: X` (the median render alone, scene set-up excluded), on
/// Linux `render_cpu_seconds: C` (the CPU time of all the process's threads per render, mean
/// over the repeats), the camera paths and rays of one render (`paths: N`, `rays: M`), and
/// writes the image.
pub(super) fn run(args: Args) -> Result<()> {
    let (task, theta, _) = args.point.resolve()?;
    let o = &args.render;
    with_threads(o.threads, || {
        let spp = o.spp.unwrap_or(task.defaults().spp);
        let scene = task.scene(&theta, o.view());
        let settings = render::Settings::new(spp, o.seed, task.max_depth());
        let mut image = None;
        let cpu = cpu_seconds();
        let seconds = super::median_seconds(args.repeat, || {
            image = Some(render::render(&scene, &settings));
        });
        println!("render_seconds: {seconds:.6}");
        if let (Some(start), Some(end)) = (cpu, cpu_seconds()) {
            println!(
                "render_cpu_seconds: {:.6}",
                (end - start) / args.repeat as f64
            );
        }
        // The work of one render (counted in a separate, untimed render: the same image).
        let (_, work) = render::render_counted(&scene, &settings);
        println!("paths: {}\nrays: {}", work.paths, work.rays);
        if let Some(image) = image {
            image.save(&args.out)?;
        }
        Ok(())
    })
}

/// CPU seconds the process's threads have run so far: on Linux the sum of the first field
/// (nanoseconds on a CPU) of every `/proc/self/task/*/schedstat`; None where that is missing.
/// Unlike wall time it leaves out the time other jobs held the cores.
fn cpu_seconds() -> Option<f64> {
    let mut ns = 0u64;
    for entry in std::fs::read_dir("/proc/self/task").ok()? {
        let text = std::fs::read_to_string(entry.ok()?.path().join("schedstat")).ok()?;
        ns += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(ns as f64 * 1e-9)
}
