//! Ask and tell against pinned results: the proof that the ask-and-tell form and the callback
//! form are one implementation. Both give, bit for bit, results recorded from the callback
//! form when it was the only form (`PINNED`). The pinned runs set `patience(0)` (adaptive)
//! and `polish(0.0)` (paper), so that the budget alone ends them as when they were recorded;
//! the lines of the runs whose values tie (`stairs-restart`, `seeded`, `batch bounds`) are
//! those of the search whose spread does not grow at a flat bottom (ties at its best level
//! with worse points around), where three such generations end a run.

use plateau_free::{
    objective::Batch, objective::Seeded, Minimizer, Objective, PlateauFreeGradient,
};

mod common;
use common::ask_tell::*;

/// Results of the callback form, recorded when it was the only form and recorded again only
/// where the behaviour was changed on purpose (CHANGELOG.md): every `minimize` run evaluates
/// its start first (`paper`'s budget is 802, `1 + 200 * 4 + 1`, so that it makes 200
/// iterations), and the paper's loop clamps its perturbed points onto the bounds.
const PINNED: [&str; 30] = [
    "rosen s0: x=[3fefffffffeaa605, 3ff0000000292219, 3ff000000035294c, 3ff00000006ae86b] fun=3c9d490957f83d6d ev=3000 it=279 re=1 sigma=3f4e7a28f1f0ade4 stop=Budget",
    "stairs-restart s0: x=[3fd86d4ed73caa81, 3fe7063d708eb3af, 4002a8db0749c850] fun=0 ev=2500 it=82 re=6 sigma=3ff8000000000000 stop=Budget",
    "seeded s0: x=[3fb0165a9cd5a11e, 3ff05d755a695b06, 3ffe1fb1ccc6a1bd] fun=0 ev=1500 it=188 re=1 sigma=400fd92bff010c1c stop=Budget",
    "batch bounds s0: x=[bfcf949177776b85, 3fed2a618abd5e82, 3ffc9bf19593cdad] fun=3fa3f7ced916872b ev=120 it=11 re=1 sigma=3ff2393ab3f743db stop=Target",
    "noresart s0: x=[3feffffffd32c3b1, 3feffffffa079d62] fun=3c954ebbfdcb2061 ev=625 it=104 re=0 sigma=3ee5a500c2da210d stop=Converged",
    "paper s0: x=[bfdda3a85c36ccca, 3fe99df27aa02561, 3ffcc2631b226a36] fun=0 ev=802 it=200 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "paper seeded bounds s0: x=[bf7142e042156f30, 3ff08fb3faaa7a0e, 400059778ebb6312] fun=0 ev=402 it=100 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "optimizer radial s0: hash=488e5391b9a29c9b ev=360 last=[3fa0419aa4b722e6, 3ff1293d93029d06, 4000424b0ecbc8d8]",
    "optimizer percoord s0: hash=cd06de1840ff104e ev=360 last=[bfac5a1107daf1a1, 3ff1df37d2be7bff, 3ffea01385e0e328]",
    "optimizer gauss-orth s0: hash=c63d04b76d3108d3 ev=360 last=[3f952fc3f755680a, 3fe87890dad848aa, 3ffdbe35c970643b]",
    "rosen s1: x=[3fefffffff815440, 3fefffffff0569cc, 3feffffffe113b29, 3feffffffc6576eb] fun=3c87b9a74e79d8d2 ev=3000 it=281 re=1 sigma=3f7a8bfc51610566 stop=Budget",
    "stairs-restart s1: x=[3fd8d1cf99897b85, 3fe1eb9ce0886c74, 3fffafa8d8817ed0] fun=0 ev=2500 it=138 re=2 sigma=4055c685caf0509c stop=Budget",
    "seeded s1: x=[3fd4b9090e972733, 3fe303e73a4ef2a7, 3ffc82644995e37e] fun=3f50624dd2f1a9fc ev=1500 it=184 re=1 sigma=402f3ea712447732 stop=Budget",
    "batch bounds s1: x=[3fb04a63af733120, 3fec8039d75c6107, 40031eebf3bbec84] fun=3f86872b020c49ba ev=29 it=4 re=0 sigma=3ff2e2318c710421 stop=Target",
    "noresart s1: x=[3fefffffff68de83, 3feffffffec4329b] fun=3c441af2181be9a0 ev=565 it=94 re=0 sigma=3ecff4afe7e31f37 stop=Converged",
    "paper s1: x=[bf64edc2f9e53380, 3ff41febd09f0748, 3fffc0d84e2406c0] fun=0 ev=802 it=200 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "paper seeded bounds s1: x=[3fd15aae5f392090, 3fee79af35e50eb7, 40010b11ab74318b] fun=3f50624dd2f1a9fc ev=402 it=100 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "optimizer radial s1: hash=742dc9554f80170d ev=360 last=[3fa1ed048af409db, 3ff0d062ee6d3ca5, 4000a82206468709]",
    "optimizer percoord s1: hash=16e513827f772944 ev=360 last=[3fa5ae8fa57cd2ab, 3ff166619d0d6d5f, 4000c55437d81f1d]",
    "optimizer gauss-orth s1: hash=150e431cdd00410f ev=360 last=[3fb1cdff01b4b414, 3fee82ac4e6c8a20, 40003796eb9f74a4]",
    "rosen s2: x=[3ff00000003048a6, 3ff00000005b310c, 3ff00000007c03d2, 3ff000000092f022] fun=3cb53bc6204a1018 ev=3000 it=283 re=1 sigma=3f5e5ff55d5a9ae3 stop=Budget",
    "stairs-restart s2: x=[3fce480749f6397c, 3fe21f700c668046, 3fff8059bfbb437c] fun=0 ev=2500 it=75 re=4 sigma=400887c4fc84cfee stop=Budget",
    "seeded s2: x=[3fc10169d856d3c9, 3fe295b67950c112, 3ffdcbd8011bf856] fun=0 ev=1500 it=194 re=1 sigma=4008f18085a8280b stop=Budget",
    "batch bounds s2: x=[bfd5ed93b18bbbd9, 3ff5adcb00857798, 4002e001405f8f0c] fun=3f926e978d4fdf3c ev=22 it=3 re=0 sigma=3fff5c81c85e045c stop=Target",
    "noresart s2: x=[3ff00000000fd4f7, 3ff0000000220d3f] fun=3c09a70d9709a800 ev=745 it=124 re=0 sigma=3ec8b246e9720e0c stop=Converged",
    "paper s2: x=[bf9cd44060ff8820, 3ff67ce75bea803a, 4002c6ed41240a3b] fun=0 ev=802 it=200 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "paper seeded bounds s2: x=[3fad736aa325fa36, 3ff24d7df8d08756, 3fffbcbffee5eb98] fun=3f60624dd2f1a9fc ev=402 it=100 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "optimizer radial s2: hash=662265b88e3c3a8 ev=360 last=[bfb419cc16d78051, 3ff0f1adc8147caa, 40001b5779ed8c93]",
    "optimizer percoord s2: hash=3b09ce261c951fd7 ev=360 last=[3faf6e321df93f27, 3ff0909d94cc13d8, 4001080874cdaaae]",
    "optimizer gauss-orth s2: hash=492a6b7a46efbc3d ev=360 last=[bfa7d8d61f35508b, 3feb115319d6460b, 3ffcdb8b48ae34ce]",
];

/// The options of every pinned `minimize` case, by name; the objective is a `Seeded` one
/// (`noisy`) for the names that say so, else `rosen` or `stairs`.
#[allow(clippy::type_complexity)]
fn minimize_cases(
    seed: u64,
) -> Vec<(
    String,
    Minimizer<plateau_free::objective::NoObjective>,
    Vec<f64>,
    fn(&[f64], u64) -> f64,
)> {
    let plain_rosen: fn(&[f64], u64) -> f64 = |x, _| rosen(x);
    let plain_stairs: fn(&[f64], u64) -> f64 = |x, _| stairs(x);
    let m = Minimizer::without_objective;
    vec![
        (
            format!("rosen s{seed}"),
            m().budget(3000).seed(seed).patience(0),
            vec![0.0; 4],
            plain_rosen,
        ),
        (
            format!("stairs-restart s{seed}"),
            m().budget(2500).seed(seed).population(6).patience(0),
            vec![3.0, -2.0, 0.5],
            plain_stairs,
        ),
        (
            format!("seeded s{seed}"),
            m().budget(1500).seed(seed).patience(0),
            vec![0.0; 3],
            noisy,
        ),
        (
            format!("batch bounds s{seed}"),
            m().budget(1200)
                .seed(seed)
                .bounds(vec![-1.0; 3], vec![4.0; 3])
                .target(0.05),
            vec![0.0; 3],
            noisy,
        ),
        (
            format!("noresart s{seed}"),
            m().budget(20000).seed(seed).restarts(false),
            vec![0.5; 2],
            plain_rosen,
        ),
        (
            format!("paper s{seed}"),
            m().budget(802).seed(seed).strategy(PAPER).polish(0.0),
            vec![0.0; 3],
            plain_stairs,
        ),
        (
            format!("paper seeded bounds s{seed}"),
            m().budget(402)
                .seed(seed)
                .strategy(PAPER)
                .polish(0.0)
                .bounds(vec![-1.0; 3], vec![2.5; 3]),
            vec![0.0; 3],
            noisy,
        ),
    ]
}

#[test]
fn ask_and_tell_gives_the_pinned_results_of_the_callback_form() {
    let mut lines = Vec::new();
    for seed in 0..3u64 {
        for (tag, minimizer, x0, f) in minimize_cases(seed) {
            lines.push(show(&tag, &drive(minimizer.ask_tell(&x0).unwrap(), f)));
        }
        for (tag, sampling, antithetic, orthogonal) in LOOPS {
            let grad = loop_estimator(
                PlateauFreeGradient::new(Seeded(noisy)),
                seed,
                sampling,
                antithetic,
                orthogonal,
            );
            // Only the configuration is used: the objective stays behind.
            let run = loop_optimizer().ask_tell(grad, &LOOP_START).unwrap();
            lines.push(show_history(
                &format!("{tag} s{seed}"),
                &drive_paper(run, noisy),
            ));
        }
    }
    // The order of the lines printed by the recording program.
    let mut expected: Vec<&str> = PINNED.to_vec();
    let key = |l: &str| l.split(':').next().unwrap().to_owned();
    expected.sort_by_key(|l| key(l));
    lines.sort_by_key(|l| key(l));
    assert_eq!(lines.len(), expected.len());
    let mismatches: Vec<String> = lines
        .iter()
        .zip(&expected)
        .filter(|(got, want)| got != want)
        .map(|(got, want)| format!("got  {got}\nwant {want}"))
        .collect();
    assert!(mismatches.is_empty(), "{}", mismatches.join("\n"));
}

/// The line `PINNED` holds for `tag`.
fn pinned(tag: &str) -> &'static str {
    PINNED
        .iter()
        .find(|l| l.starts_with(&format!("{tag}:")))
        .unwrap_or_else(|| panic!("no pinned line for {tag}"))
}

/// Runs `minimizer` (the callback form) from `x0` and compares its result with the line
/// pinned for `tag`.
fn assert_run_is_pinned<F: Objective>(tag: &str, minimizer: Minimizer<F>, x0: &[f64]) {
    assert_eq!(show(tag, &minimizer.run(x0).unwrap()), pinned(tag));
}

#[test]
fn the_callback_form_still_gives_the_pinned_results() {
    for seed in 0..3u64 {
        let tag = |name: &str| format!("{name} s{seed}");
        assert_run_is_pinned(
            &tag("rosen"),
            Minimizer::new(rosen).budget(3000).seed(seed).patience(0),
            &[0.0; 4],
        );
        assert_run_is_pinned(
            &tag("batch bounds"),
            Minimizer::new(Batch(noisy_batch))
                .budget(1200)
                .seed(seed)
                .bounds(vec![-1.0; 3], vec![4.0; 3])
                .target(0.05),
            &[0.0; 3],
        );
        assert_run_is_pinned(
            &tag("paper seeded bounds"),
            Minimizer::new(Seeded(noisy))
                .budget(402)
                .seed(seed)
                .strategy(PAPER)
                .polish(0.0)
                .bounds(vec![-1.0; 3], vec![2.5; 3]),
            &[0.0; 3],
        );
        for (name, sampling, antithetic, orthogonal) in LOOPS {
            let tag = tag(name);
            let mut grad = loop_estimator(
                PlateauFreeGradient::new(Seeded(noisy)),
                seed,
                sampling,
                antithetic,
                orthogonal,
            );
            let h = loop_optimizer().minimize(&mut grad, &LOOP_START).unwrap();
            assert_eq!(show_history(&tag, &h), pinned(&format!("optimizer {tag}")));
        }
    }
}
