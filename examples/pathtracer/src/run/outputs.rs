//! The files a run writes into its directory: `target.png`, `initial.png`, `final.png`,
//! `final.exr`, `progress.png`, `history.csv`, `convergence.png` and `summary.json`.

use std::fs;
use std::path::Path;

use super::{write_history, Outcome, Settings};
use crate::render::Image;
use crate::report::{self, Axes, Result, Series};
use crate::tasks::Task;

/// Writes the images, the strip, the plot, the CSV and the summary of a run.
pub(super) fn write_outputs(
    task: &Task,
    s: &Settings,
    outcome: &Outcome,
    [target, initial, final_image]: [&Image; 3],
    thetas: &[Vec<f64>],
    dir: &Path,
) -> Result<()> {
    fs::create_dir_all(dir)?;
    target.save(&dir.join("target.png"))?;
    initial.save(&dir.join("initial.png"))?;
    final_image.save(&dir.join("final.png"))?;
    final_image.save(&dir.join("final.exr"))?;

    // The progress strip: the start, five moments of the run, then the target.
    if thetas.len() > 1 {
        let view = s.view();
        let mut frames: Vec<Image> = thetas
            .iter()
            .map(|theta| task.render(theta, s.seed, s.spp, view))
            .collect();
        frames.push(target.clone());
        report::strip(&frames).save(&dir.join("progress.png"))?;
    }

    let h = &outcome.history;
    write_history(&dir.join("history.csv"), h)?;
    let title = format!("{}: {}", task.name().to_uppercase(), s.label());
    report::plot(
        &dir.join("convergence.png"),
        &Axes::log_y(&title, "iteration (a step of the method)", "MSE"),
        &[
            Series::line(
                "image MSE",
                h.iter()
                    .filter_map(|r| r.image_mse.map(|v| (r.iteration as f64, v)))
                    .collect(),
            ),
            Series::line(
                "parameter MSE",
                h.iter()
                    .map(|r| (r.iteration as f64, r.param_mse))
                    .collect(),
            ),
        ],
    )?;
    fs::write(
        dir.join("summary.json"),
        serde_json::to_string_pretty(&outcome.summary)?,
    )?;
    Ok(())
}
