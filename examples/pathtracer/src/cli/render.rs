//! `render <task>`: one image at the target, the start or given parameters, and its time.

use std::path::PathBuf;

use super::{find_task, with_threads, RenderOptions};
use crate::render;
use crate::report::Result;

/// The options of `render`.
#[derive(clap::Args)]
pub(super) struct Args {
    task: String,
    /// The start parameters.
    #[arg(long, conflicts_with_all = ["target", "params"])]
    initial: bool,
    /// The target parameters (the default).
    #[arg(long, conflicts_with = "params")]
    target: bool,
    /// Explicit parameters, comma-separated.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    params: Option<Vec<f64>>,
    #[command(flatten)]
    render: RenderOptions,
    /// Render this many times and print the median time (the image is the last one).
    #[arg(long, default_value_t = 1)]
    repeat: usize,
    /// A .png (sRGB) or .exr (linear) file.
    #[arg(long)]
    out: PathBuf,
}

/// Renders, prints `render_seconds: X` (the median render alone, scene set-up excluded) and
/// writes the image.
pub(super) fn run(args: Args) -> Result<()> {
    let task = find_task(&args.task)?;
    let theta = match args.params {
        Some(p) => p,
        None if args.initial => task.start(),
        None => task.target(),
    };
    if theta.len() != task.dim() {
        return Err(format!(
            "{} takes {} parameters, got {}",
            task.name(),
            task.dim(),
            theta.len()
        )
        .into());
    }
    if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
        return Err(format!("parameter {i} is {}", theta[i]).into());
    }
    let o = &args.render;
    with_threads(o.threads, || {
        let spp = o.spp.unwrap_or(task.defaults().spp);
        let scene = task.scene(&theta, o.view());
        let settings = render::Settings::new(spp, o.seed, task.max_depth());
        let mut image = None;
        let seconds = super::median_seconds(args.repeat, || {
            image = Some(render::render(&scene, &settings));
        });
        println!("render_seconds: {seconds:.6}");
        if let Some(image) = image {
            image.save(&args.out)?;
        }
        Ok(())
    })
}
