//! Fitting a run into a time budget (`optimize --budget SECONDS`).

use std::time::Instant;

use super::{eval_every, Settings, CURVE_POINTS};
use crate::tasks::Task;

/// Settings that fit a run into `budget` seconds, and a line saying what was chosen: times one
/// render at the defaults, then [`plan_with_render_time`].
pub fn plan_for_budget(task: &Task, s: &Settings, budget: f64) -> (Settings, String) {
    let view = s.view();
    // One warm-up render (caches, thread pool), then the timed one.
    let _ = task.render(&task.start(), s.seed, s.spp, view);
    let t = Instant::now();
    let _ = task.render(&task.start(), s.seed, s.spp, view);
    plan_with_render_time(t.elapsed().as_secs_f64(), s, budget)
}

/// The budget planner given the time of one render at the defaults.
///
/// The cost model: an iteration costs N renders, and a render's time is proportional to spp
/// times pixels (`experiment tradeoff` finds each close to linear on SHADOW and GI). The
/// order of the cuts follows the same study's errors (docs/results/tradeoff.md): iterations
/// are kept (the annealing schedule needs them); the resolution goes first, down to half (on
/// GI a quarter of the pixels kept the default's error, while a quarter of the spp made it
/// worse); then spp, halved down to 4 at half resolution; then the resolution again, to a
/// quarter (on GI far worse: the last resort before fewer iterations); only then fewer
/// iterations. The loop also stops when the budget is spent.
pub fn plan_with_render_time(render: f64, s: &Settings, budget: f64) -> (Settings, String) {
    let evaluations = s.iterations as f64 * s.samples.max(1) as f64;
    let predicted =
        |scale: f64, spp: u32| render * evaluations * (scale * scale) * (spp as f64 / s.spp as f64);
    let mut plan = s.clone();
    plan.budget_seconds = Some(budget);
    let base_scale = s.scale.unwrap_or(1.0);
    if predicted(1.0, s.spp) <= budget {
        return (
            plan,
            format!(
                "budget {budget} s: defaults fit (predicted {:.1} s)",
                predicted(1.0, s.spp)
            ),
        );
    }
    let mut spps = vec![s.spp];
    while spps.last().is_some_and(|&v| v / 2 >= 4) {
        spps.push(spps.last().copied().unwrap_or(4) / 2);
    }
    let fewest = spps.last().copied().unwrap_or(s.spp);
    let cuts: Vec<(f64, u32)> = [(1.0, s.spp), (0.75, s.spp)]
        .into_iter()
        .chain(spps.iter().map(|&spp| (0.5, spp)))
        .chain([(0.35, fewest), (0.25, fewest)])
        .collect();
    let chosen = cuts
        .iter()
        .copied()
        .find(|&(scale, spp)| predicted(scale, spp) <= budget);
    let (scale, spp) = chosen.unwrap_or((0.25, fewest));
    plan.scale = Some(base_scale * scale);
    plan.spp = spp;
    let per_iteration = predicted(scale, spp) / s.iterations as f64;
    if chosen.is_none() {
        plan.iterations = ((budget / per_iteration) as usize).max(1);
        plan.eval_every = eval_every(plan.iterations, CURVE_POINTS);
    }
    let why = format!(
        "budget {budget} s: one render takes {render:.4} s at the defaults; chose resolution scale {:.2}, {} spp, {} iterations (predicted {:.1} s)",
        base_scale * scale,
        spp,
        plan.iterations,
        per_iteration * plan.iterations as f64
    );
    (plan, why)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tasks;

    /// The planner's order of cuts: resolution to half, then spp to 4, then a quarter of the
    /// resolution, then iterations; and what it picks always fits the budget.
    #[test]
    fn budget_planner_cuts_resolution_then_spp_then_iterations() {
        let shadow = tasks::by_name("shadow").unwrap();
        let s = Settings::defaults(&shadow); // N 2, 32 spp, 400 iterations
        let full = 0.1 * 800.0; // 0.1 s per render, 800 renders
        let pick = |fraction: f64| {
            let (p, _) = plan_with_render_time(0.1, &s, fraction * full);
            (p.scale.unwrap_or(1.0), p.spp, p.iterations)
        };
        assert_eq!(pick(1.0), (1.0, 32, 400));
        assert_eq!(pick(0.6), (0.75, 32, 400));
        assert_eq!(pick(0.25), (0.5, 32, 400));
        assert_eq!(pick(0.2), (0.5, 16, 400));
        assert_eq!(pick(0.25 / 8.0), (0.5, 4, 400));
        assert_eq!(pick(0.03), (0.35, 4, 400));
        assert_eq!(pick(0.25 * 0.25 / 8.0), (0.25, 4, 400));
        let (scale, spp, iterations) = pick(0.001);
        assert_eq!((scale, spp), (0.25, 4));
        assert!((1..400).contains(&iterations));
        for fraction in [0.9, 0.3, 0.1, 0.02, 0.005, 0.001] {
            let (p, _) = plan_with_render_time(0.1, &s, fraction * full);
            let predicted = 0.1
                * (p.iterations * p.samples) as f64
                * p.scale.unwrap_or(1.0).powi(2)
                * p.spp as f64
                / s.spp as f64;
            assert!(
                predicted <= fraction * full * 1.000001,
                "{fraction}: {predicted}"
            );
        }
    }
}
