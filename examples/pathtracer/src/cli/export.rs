//! `export <task>`: the task's scene at the target, the start or given parameters, written
//! for another renderer (`scene.json` and its files; see [`crate::export`]).

use std::path::PathBuf;

use super::point::Point;
use super::values;
use crate::export::{self, Header};
use crate::render::Settings;
use crate::report::Result;
use crate::tasks::View;

/// The options of `export`.
#[derive(clap::Args)]
pub(super) struct Args {
    #[command(flatten)]
    point: Point,
    /// Samples per pixel the description asks for [default: the task's, supplemental Table 1].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1u32))]
    spp: Option<u32>,
    /// Resolution multiplier, as `render --scale` [default: 1].
    #[arg(long, allow_hyphen_values = true, value_parser = values::scale)]
    scale: Option<f64>,
    /// The directory to write `scene.json` and its mesh and texture files into (made if missing).
    #[arg(long, value_parser = values::out_dir)]
    out: PathBuf,
}

/// Writes the description and prints the path of `scene.json`.
pub(super) fn run(args: Args) -> Result<()> {
    let (task, theta, which) = args.point.resolve()?;
    let view = View {
        scale: args.scale,
        ..View::default()
    };
    let scene = task.scene(&theta, view);
    let header = Header {
        task: task.name(),
        params: which,
        theta: &theta,
        settings: Settings::new(args.spp.unwrap_or(task.defaults().spp), 0, task.max_depth()),
        defaults: Some((task.defaults(), task.bounds().is_some(), task.periodic())),
        paper: task.paper(),
    };
    std::fs::create_dir_all(&args.out)?;
    export::write(&args.out, &header, &scene)?;
    println!("{}", args.out.join("scene.json").display());
    Ok(())
}
