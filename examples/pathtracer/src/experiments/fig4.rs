//! Supplemental Fig. 4: the TEXTURE task (49,152 parameters), one run with all its outputs.

use super::{task, write_page, Options};
use crate::report::{self, sci, Result};
use crate::run::{self, Settings};

pub(super) fn run(opts: &Options) -> Result<()> {
    let t = task("texture")?;
    let mut s = Settings::defaults(&t);
    opts.shrink(&mut s, 30);
    let dir = opts.out.join("fig4");
    let o = run::optimize(&t, &s, Some(&dir), false)?;
    run::write_history(&opts.out.join("fig4.csv"), &o.history)?;
    let m = &o.summary;
    let body = format!(
        "{} parameters, N = {}, sigma0 = {}, lr = {}, {} iterations, {} spp.\n\n![convergence](fig4/convergence.png)\n\nTarget, start and result: ![target](fig4/target.png) ![initial](fig4/initial.png) ![final](fig4/final.png)\n\n{}",
        m.dim,
        m.samples,
        m.sigma0,
        m.lr,
        m.iterations,
        m.spp,
        report::markdown_table(
            &["", "image MSE", "parameter MSE"],
            &[vec!["start".into(), sci(m.initial_image_mse), sci(m.initial_param_mse)], vec!["end".into(), sci(m.image_mse), sci(m.param_mse)]]
        )
    );
    // Whether the run was still improving: the parameter error over its last tenth.
    let tail = o.history.len() - o.history.len() / 10;
    let before = o
        .history
        .get(tail.saturating_sub(1))
        .map_or(f64::NAN, |r| r.param_mse);
    let body = format!(
        "{body}\nOver the run the image MSE fell {:.1}x and the parameter MSE {:.1}x; over its last tenth the parameter MSE changed by {:+.1} % (from {} to {}): {}.\n",
        m.initial_image_mse / m.image_mse,
        m.initial_param_mse / m.param_mse,
        100.0 * (m.param_mse / before - 1.0),
        sci(before),
        sci(m.param_mse),
        if m.param_mse < 0.99 * before {
            "still falling, so more iterations would go on improving it"
        } else {
            "levelled off"
        }
    );
    write_page(
        opts,
        "fig4",
        "Supplemental Fig. 4: TEXTURE (49,152 parameters)",
        &body,
    )
}
