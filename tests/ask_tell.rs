//! Ask and tell: the optimiser hands out each iteration's points and takes their values back.
//!
//! The proof that the ask-and-tell form and the callback form are one implementation: both
//! give, bit for bit, results recorded from the callback form when it was the only form
//! (`PINNED`), and each other's results for every form of objective, with and without
//! parallel evaluation. The pinned runs set `patience(0)` (adaptive) and `polish(0.0)`
//! (paper), so that the budget alone ends them as when they were recorded; the lines of the
//! runs whose values tie (`stairs-restart`, `seeded`, `batch bounds`) are those of the search
//! whose spread does not grow at a flat bottom (ties at its best level with worse points
//! around), where three such generations end a run. Then the
//! errors: asking twice, telling without asking, the wrong number of values, non-finite
//! values, a result taken too early.

use std::cell::RefCell;

use plateau_free::{
    Adam, Annealer, Ask, AskTell, Batch, Error, FailurePolicy, Minimizer, Minimum, Objective,
    OnFailure, Optimizer, OptimizerState, PaperAskTell, PlateauFreeGradient, Points, Sampling,
    Seeded, Stop, Strategy,
};

fn rosen(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
        .sum()
}

/// A staircase with its minimum 0 at `(0, 1, 2, ...)`: flat almost everywhere.
fn stairs(x: &[f64]) -> f64 {
    x.iter()
        .enumerate()
        .map(|(i, v)| (v.round() - i as f64).powi(2))
        .sum()
}

/// The staircase with noise that depends on the seed alone (a renderer's noise).
fn noisy(x: &[f64], seed: u64) -> f64 {
    stairs(x) + 1e-3 * (seed % 97) as f64
}

/// `noisy` as a batch objective.
fn noisy_batch(p: Points<'_>, s: &[u64], out: &mut [f64]) {
    for ((x, &seed), o) in p.iter().zip(s).zip(out.iter_mut()) {
        *o = noisy(x, seed);
    }
}

const PAPER: Strategy = Strategy::Paper {
    samples: 4,
    lr: 0.05,
    sigma0: 1.0,
};

/// The values of an ask, computed "elsewhere": the points copied out, evaluated last to
/// first (the order must not matter), the values put back in the points' order.
fn evaluate_elsewhere(ask: Ask<'_>, f: impl Fn(&[f64], u64) -> f64) -> Vec<f64> {
    let jobs: Vec<(Vec<f64>, u64)> = ask.iter().map(|(x, s)| (x.to_vec(), s)).collect();
    let mut values = vec![0.0; jobs.len()];
    for (k, (x, seed)) in jobs.iter().enumerate().rev() {
        values[k] = f(x, *seed);
    }
    values
}

/// Drives an ask-and-tell `minimize` run to its end.
fn drive(mut run: AskTell, f: impl Fn(&[f64], u64) -> f64) -> Minimum {
    while let Some(ask) = run.ask().unwrap() {
        let values = evaluate_elsewhere(ask, &f);
        run.tell(&values).unwrap();
    }
    assert!(run.is_done());
    assert!(
        run.ask().unwrap().is_none(),
        "a finished run asks for nothing"
    );
    run.finish().unwrap()
}

/// Drives an ask-and-tell paper loop to its end.
fn drive_paper(mut run: PaperAskTell, f: impl Fn(&[f64], u64) -> f64) -> plateau_free::History {
    while let Some(ask) = run.ask().unwrap() {
        let values = evaluate_elsewhere(ask, &f);
        run.tell(&values).unwrap();
    }
    run.finish()
}

/// The line `PINNED` holds for a result.
fn show(tag: &str, m: &Minimum) -> String {
    let bits: Vec<u64> = m.x.iter().map(|v| v.to_bits()).collect();
    format!(
        "{tag}: x={:x?} fun={:x} ev={} it={} re={} sigma={:x} stop={:?}",
        bits,
        m.fun.to_bits(),
        m.evaluations,
        m.iterations,
        m.restarts,
        m.sigma.to_bits(),
        m.stop
    )
}

/// The line `PINNED` holds for a paper loop's history.
fn show_history(tag: &str, h: &plateau_free::History) -> String {
    let bits: Vec<u64> = h
        .theta
        .iter()
        .flatten()
        .chain(&h.value)
        .chain(&h.sigma)
        .map(|v| v.to_bits())
        .collect();
    let hash = bits
        .iter()
        .fold(0u64, |a, b| plateau_free::seeding::mix(a ^ b));
    let last: Vec<u64> = h
        .last_theta()
        .unwrap()
        .iter()
        .map(|v| v.to_bits())
        .collect();
    format!(
        "optimizer {tag}: hash={hash:x} ev={} last={last:x?}",
        h.evaluations
    )
}

/// Results of the callback form, recorded when it was the only form and recorded again only
/// where the behaviour was changed on purpose (CHANGELOG.md): every `minimize` run evaluates
/// its start first (`paper`'s budget is 802, `1 + 200 * 4 + 1`, so that it makes 200
/// iterations), and the paper's loop clamps its perturbed points onto the bounds.
const PINNED: [&str; 30] = [
    "rosen s0: x=[3ff0000000130473, 3ff000000034fdec, 3ff0000000696d8d, 3ff0000000dd448d] fun=3c673502bd14c740 ev=3000 it=272 re=2 sigma=3fe24b957db23748 stop=Budget",
    "stairs-restart s0: x=[3fd86d4ed73caa81, 3fe7063d708eb3af, 4002a8db0749c850] fun=0 ev=2500 it=76 re=6 sigma=3ff8000000000000 stop=Budget",
    "seeded s0: x=[3fb0165a9cd5a11e, 3ff05d755a695b06, 3ffe1fb1ccc6a1bd] fun=0 ev=1500 it=188 re=1 sigma=40283e271b12523e stop=Budget",
    "batch bounds s0: x=[3fd1f92aa07701f6, 3fec974788459b53, 3ffff377a307bf4e] fun=3f86872b020c49ba ev=106 it=10 re=1 sigma=3ff083d1ea9aabf2 stop=Target",
    "noresart s0: x=[3feffffffd32c3b1, 3feffffffa079d62] fun=3c954ebbfdcb2061 ev=625 it=104 re=0 sigma=3ee5a500c2da210d stop=Converged",
    "paper s0: x=[bfdda3a85c36ccca, 3fe99df27aa02561, 3ffcc2631b226a36] fun=0 ev=802 it=200 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "paper seeded bounds s0: x=[bf7142e042156f30, 3ff08fb3faaa7a0e, 400059778ebb6312] fun=0 ev=402 it=100 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "optimizer radial s0: hash=488e5391b9a29c9b ev=360 last=[3fa0419aa4b722e6, 3ff1293d93029d06, 4000424b0ecbc8d8]",
    "optimizer percoord s0: hash=cd06de1840ff104e ev=360 last=[bfac5a1107daf1a1, 3ff1df37d2be7bff, 3ffea01385e0e328]",
    "optimizer gauss-orth s0: hash=c63d04b76d3108d3 ev=360 last=[3f952fc3f755680a, 3fe87890dad848aa, 3ffdbe35c970643b]",
    "rosen s1: x=[3ff0000000449b7f, 3ff0000000872a62, 3ff00000011c2ea7, 3ff0000002362270] fun=3c7e3becff435ca0 ev=3000 it=274 re=2 sigma=3fcd36f64f8917ec stop=Budget",
    "stairs-restart s1: x=[3fd8d1cf99897b85, 3fe1eb9ce0886c74, 3fffafa8d8817ed0] fun=0 ev=2500 it=62 re=6 sigma=3ff8000000000000 stop=Budget",
    "seeded s1: x=[3fd4b9090e972733, 3fe303e73a4ef2a7, 3ffc82644995e37e] fun=3f50624dd2f1a9fc ev=1500 it=184 re=1 sigma=4032823880a055ad stop=Budget",
    "batch bounds s1: x=[3fb04a63af733120, 3fec8039d75c6107, 40031eebf3bbec84] fun=3f86872b020c49ba ev=29 it=4 re=0 sigma=3ff2e2318c710421 stop=Target",
    "noresart s1: x=[3fefffffff68de83, 3feffffffec4329b] fun=3c441af2181be9a0 ev=565 it=94 re=0 sigma=3ecff4afe7e31f37 stop=Converged",
    "paper s1: x=[bf64edc2f9e53380, 3ff41febd09f0748, 3fffc0d84e2406c0] fun=0 ev=802 it=200 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "paper seeded bounds s1: x=[3fd15aae5f392090, 3fee79af35e50eb7, 40010b11ab74318b] fun=3f50624dd2f1a9fc ev=402 it=100 re=0 sigma=3f847ae147ae1480 stop=Budget",
    "optimizer radial s1: hash=742dc9554f80170d ev=360 last=[3fa1ed048af409db, 3ff0d062ee6d3ca5, 4000a82206468709]",
    "optimizer percoord s1: hash=16e513827f772944 ev=360 last=[3fa5ae8fa57cd2ab, 3ff166619d0d6d5f, 4000c55437d81f1d]",
    "optimizer gauss-orth s1: hash=150e431cdd00410f ev=360 last=[3fb1cdff01b4b414, 3fee82ac4e6c8a20, 40003796eb9f74a4]",
    "rosen s2: x=[3fefffffffeac8ff, 3fefffffffc554b6, 3fefffffff6c27fd, 3feffffffeeef601] fun=3c67fbe3e37803b0 ev=3000 it=283 re=1 sigma=3eb4d83c56a48d63 stop=Budget",
    "stairs-restart s2: x=[3fce480749f6397c, 3fe21f700c668046, 3fff8059bfbb437c] fun=0 ev=2500 it=75 re=4 sigma=3ff86524aaf7faa8 stop=Budget",
    "seeded s2: x=[3fc10169d856d3c9, 3fe295b67950c112, 3ffdcbd8011bf856] fun=0 ev=1500 it=194 re=1 sigma=400c806faf6e6302 stop=Budget",
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
    Minimizer<plateau_free::NoObjective>,
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

/// The pinned paper loops: (name, sampler, antithetic, orthogonal).
const LOOPS: [(&str, Sampling, bool, bool); 3] = [
    ("radial", Sampling::Radial, true, false),
    ("percoord", Sampling::PerCoordinate, true, false),
    ("gauss-orth", Sampling::Gaussian, false, true),
];

fn loop_estimator<F>(
    grad: PlateauFreeGradient<F>,
    seed: u64,
    sampling: Sampling,
    antithetic: bool,
    orthogonal: bool,
) -> PlateauFreeGradient<F> {
    grad.samples(6)
        .sampling(sampling)
        .antithetic(antithetic)
        .orthogonal(orthogonal)
        .seed(seed)
        .on_failure(OnFailure::Resample { limit: 5 })
}

fn loop_optimizer() -> Optimizer {
    Optimizer::new(Adam::new(0.05).unwrap(), Annealer::paper(0.8, 60).unwrap()).record_theta(true)
}

const LOOP_START: [f64; 3] = [0.2, -0.3, 0.9];

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

/// The options of the identity tests.
fn opts<F>(m: Minimizer<F>, seed: u64, strategy: Strategy) -> Minimizer<F> {
    m.budget(900).seed(seed).strategy(strategy)
}

#[test]
fn minimize_ask_tell_equals_run_for_every_form_of_objective() {
    for seed in [0, 5, 17] {
        for strategy in [Strategy::Adaptive, PAPER] {
            let x0 = [0.3, -1.2, 2.0, 0.0];
            let told = drive(
                opts(Minimizer::without_objective(), seed, strategy)
                    .ask_tell(&x0)
                    .unwrap(),
                noisy,
            );
            let plain = opts(Minimizer::new(stairs), seed, strategy)
                .run(&x0)
                .unwrap();
            let seeded = opts(Minimizer::new(Seeded(noisy)), seed, strategy)
                .run(&x0)
                .unwrap();
            let batch = opts(Minimizer::new(Batch(noisy_batch)), seed, strategy)
                .run(&x0)
                .unwrap();
            assert_eq!(told, seeded, "seed {seed}, {strategy:?}");
            assert_eq!(told, batch, "seed {seed}, {strategy:?}");
            // Without the noise, the plain objective's run is the noiseless ask and tell's.
            let told_plain = drive(
                opts(Minimizer::without_objective(), seed, strategy)
                    .ask_tell(&x0)
                    .unwrap(),
                |x, _| stairs(x),
            );
            assert_eq!(told_plain, plain, "seed {seed}, {strategy:?}");
            // The objective a minimiser holds is not used by its ask and tell.
            let from_callback_minimizer = drive(
                opts(Minimizer::new(|_: &[f64]| f64::NAN), seed, strategy)
                    .ask_tell(&x0)
                    .unwrap(),
                noisy,
            );
            assert_eq!(from_callback_minimizer, told);
        }
    }
}

#[test]
fn paper_loop_ask_tell_equals_minimize_sequential_and_parallel() {
    for seed in [1, 2, 9] {
        for (_, sampling, antithetic, orthogonal) in LOOPS {
            let told = drive_paper(
                loop_optimizer()
                    .ask_tell(
                        loop_estimator(
                            PlateauFreeGradient::without_objective(),
                            seed,
                            sampling,
                            antithetic,
                            orthogonal,
                        ),
                        &LOOP_START,
                    )
                    .unwrap(),
                noisy,
            );
            let est = |f| {
                loop_estimator(
                    PlateauFreeGradient::new(f),
                    seed,
                    sampling,
                    antithetic,
                    orthogonal,
                )
            };
            let seq = loop_optimizer()
                .minimize(&mut est(Seeded(noisy)), &LOOP_START)
                .unwrap();
            let par = loop_optimizer()
                .minimize(&mut est(Seeded(noisy)).parallel(true), &LOOP_START)
                .unwrap();
            let batch = loop_optimizer()
                .minimize(
                    &mut loop_estimator(
                        PlateauFreeGradient::new(Batch(noisy_batch)),
                        seed,
                        sampling,
                        antithetic,
                        orthogonal,
                    ),
                    &LOOP_START,
                )
                .unwrap();
            assert_eq!(told, seq);
            assert_eq!(told, par);
            assert_eq!(told, batch);
        }
    }
}

#[test]
fn asked_seeds_are_the_seeds_the_callback_forms_receive() {
    for strategy in [Strategy::Adaptive, PAPER] {
        // The callback form's seeds, in the order of the calls.
        let log = RefCell::new(Vec::new());
        let logged = Seeded(|x: &[f64], seed: u64| {
            log.borrow_mut().push(seed);
            noisy(x, seed)
        });
        opts(Minimizer::new(logged), 4, strategy)
            .polish(0.0)
            .run(&[1.0, 2.0])
            .unwrap();
        let mut asked = Vec::new();
        let mut run = opts(Minimizer::without_objective(), 4, strategy)
            .polish(0.0)
            .ask_tell(&[1.0, 2.0])
            .unwrap();
        while let Some(ask) = run.ask().unwrap() {
            assert_eq!(ask.dim(), 2);
            assert_eq!(ask.points().len(), ask.len());
            asked.extend_from_slice(ask.seeds());
            let values = evaluate_elsewhere(ask, noisy);
            run.tell(&values).unwrap();
        }
        assert_eq!(asked, *log.borrow(), "{strategy:?}");
        assert_eq!(asked.len(), run.finish().unwrap().evaluations);
        // The start first, alone, with the run's seed. Then the adaptive search: one seed
        // per generation (the first generation's is the run's); the paper's loop: one per
        // pair, and the final evaluation's seed is the run's.
        assert_eq!(asked[0], 4);
        if strategy == PAPER {
            assert_eq!(asked[1], asked[2]);
            assert_ne!(asked[2], asked[3]);
            assert_eq!(*asked.last().unwrap(), 4);
        } else {
            assert!(asked[..7].iter().all(|&s| s == asked[0]));
        }
    }
}

#[test]
fn asking_twice_and_telling_without_asking_are_errors() {
    for strategy in [Strategy::Adaptive, PAPER] {
        let mut run = opts(Minimizer::without_objective(), 0, strategy)
            .ask_tell(&[0.5, 0.5])
            .unwrap();
        assert_eq!(run.tell(&[1.0]), Err(Error::NothingAsked));
        let first: Vec<f64> = run.ask().unwrap().unwrap().points().as_flat().to_vec();
        assert_eq!(run.ask().unwrap_err(), Error::AskPending);
        assert_eq!(
            Error::AskPending.to_string(),
            "ask called twice: the asked points still wait for their values (tell them first)"
        );
        let values: Vec<f64> = first.chunks(2).map(stairs).collect();
        run.tell(&values).unwrap();
        assert_eq!(run.tell(&values), Err(Error::NothingAsked), "told twice");
        // A paper loop on its own behaves the same.
        let grad = PlateauFreeGradient::without_objective().samples(4);
        let mut run = Optimizer::new(Adam::new(0.1).unwrap(), Annealer::constant(0.2, 3).unwrap())
            .ask_tell(grad, &[0.0])
            .unwrap();
        assert_eq!(run.tell(&[0.0; 4]), Err(Error::NothingAsked));
        run.ask().unwrap();
        assert_eq!(run.ask().unwrap_err(), Error::AskPending);
    }
}

#[test]
fn the_wrong_number_of_values_or_a_nan_changes_nothing() {
    for strategy in [Strategy::Adaptive, PAPER] {
        let clean = drive(
            opts(Minimizer::without_objective(), 3, strategy)
                .ask_tell(&[0.5, 0.5, 0.5])
                .unwrap(),
            noisy,
        );
        // The same run with mistakes in its third iteration, then corrected.
        let mut run = opts(Minimizer::without_objective(), 3, strategy)
            .on_failure(FailurePolicy::Raise)
            .ask_tell(&[0.5, 0.5, 0.5])
            .unwrap();
        let mut iteration = 0;
        while let Some(ask) = run.ask().unwrap() {
            let values = evaluate_elsewhere(ask, noisy);
            if iteration == 2 {
                let k = values.len();
                assert_eq!(
                    run.tell(&values[..k - 1]),
                    Err(Error::TellCount {
                        expected: k,
                        got: k - 1
                    })
                );
                assert_eq!(
                    Error::TellCount {
                        expected: 8,
                        got: 7
                    }
                    .to_string(),
                    "tell got 7 values for 8 asked points"
                );
                let mut bad = values.clone();
                bad[1] = f64::NAN;
                match run.tell(&bad) {
                    Err(Error::NonFiniteValue {
                        sample,
                        value,
                        point,
                    }) => {
                        assert!(value.is_nan());
                        // The adaptive search counts evaluations over the run, the paper's
                        // loop within the estimate (as their callback forms do).
                        let first = if strategy == PAPER {
                            0
                        } else {
                            run.evaluations()
                        };
                        assert_eq!(sample, first + 1);
                        assert_eq!(point.len(), 3);
                    }
                    other => panic!("{other:?}"),
                }
                bad[1] = f64::NEG_INFINITY;
                assert!(matches!(run.tell(&bad), Err(Error::NonFiniteValue { .. })));
            }
            run.tell(&values).unwrap();
            iteration += 1;
        }
        assert_eq!(run.finish().unwrap(), clean, "{strategy:?}");
    }
}

#[test]
fn a_nan_fails_as_in_the_callback_form() {
    // f is NaN on part of the line: the callback form's error, and ask and tell's, agree.
    let f = |x: &[f64]| {
        if x[0] > 2.0 {
            f64::NAN
        } else {
            (x[0] - 3.0).powi(2)
        }
    };
    for strategy in [Strategy::Adaptive, PAPER] {
        let called = opts(Minimizer::new(f), 2, strategy)
            .on_failure(FailurePolicy::Raise)
            .run(&[0.0])
            .unwrap_err();
        let mut run = opts(Minimizer::without_objective(), 2, strategy)
            .on_failure(FailurePolicy::Raise)
            .ask_tell(&[0.0])
            .unwrap();
        let told = loop {
            let ask = run.ask().unwrap().expect("fails before the end");
            let values = evaluate_elsewhere(ask, |x, _| f(x));
            if let Err(e) = run.tell(&values) {
                break e;
            }
        };
        // (NaN != NaN: compared by the message, which names the evaluation and the point.)
        assert_eq!(told.to_string(), called.to_string(), "{strategy:?}");
        assert!(matches!(told, Error::NonFiniteValue { .. }), "{told}");
    }
}

#[test]
fn resampling_in_the_paper_loop_redraws_at_the_next_ask() {
    // NaN on a quarter of the line: estimates are redrawn until every value is finite.
    let f = |x: &[f64]| {
        if x[0].fract().abs() < 0.25 {
            f64::NAN
        } else {
            (x[0] - 2.0).abs()
        }
    };
    let policy = OnFailure::Resample { limit: 50 };
    let opt = || {
        Optimizer::new(
            Adam::new(0.1).unwrap(),
            Annealer::constant(0.4, 40).unwrap(),
        )
    };
    let called = opt()
        .minimize(
            &mut PlateauFreeGradient::new(f)
                .samples(4)
                .seed(8)
                .on_failure(policy),
            &[0.6],
        )
        .unwrap();
    let grad = PlateauFreeGradient::without_objective()
        .samples(4)
        .seed(8)
        .on_failure(policy);
    let mut run = opt().ask_tell(grad, &[0.6]).unwrap();
    let (mut asks, mut redraws) = (0, 0);
    loop {
        let iteration = run.iteration();
        let Some(ask) = run.ask().unwrap() else {
            break;
        };
        asks += 1;
        let values = evaluate_elsewhere(ask, |x, _| f(x));
        run.tell(&values).unwrap();
        if run.iteration() == iteration {
            redraws += 1;
            assert!(values.iter().any(|v| v.is_nan()));
        } else {
            assert_eq!(run.last_estimate().unwrap().resampled, redraws);
            redraws = 0;
        }
    }
    assert!(asks > 40, "some estimates were redrawn: {asks} asks");
    assert_eq!(run.finish(), called);
}

#[test]
fn a_paper_loop_stopped_and_continued_from_its_state_is_the_whole_run() {
    let grad = || PlateauFreeGradient::without_objective().samples(6).seed(21);
    let whole = drive_paper(
        loop_optimizer().ask_tell(grad(), &LOOP_START).unwrap(),
        noisy,
    );
    let mut run = loop_optimizer().ask_tell(grad(), &LOOP_START).unwrap();
    for _ in 0..25 {
        let ask = run.ask().unwrap().unwrap();
        let values = evaluate_elsewhere(ask, noisy);
        run.tell(&values).unwrap();
    }
    // An iteration in progress is repeated by the continued run.
    run.ask().unwrap();
    let saved: OptimizerState = run.state();
    assert_eq!(saved.iteration, 25);
    let early = run.finish();
    assert!(early.stopped_early);
    assert_eq!(early.iterations(), 25);
    // Continued by ask and tell, and by the callback form.
    let continued = loop_optimizer()
        .ask_tell_from(grad(), saved.clone())
        .unwrap();
    assert_eq!(drive_paper(continued, noisy), whole);
    let mut callback = PlateauFreeGradient::new(Seeded(noisy)).samples(6).seed(21);
    let state = loop_optimizer()
        .minimize_from(
            &mut callback,
            saved,
            |_| std::ops::ControlFlow::Continue(()),
        )
        .unwrap();
    assert_eq!(state.history, whole);
}

#[test]
fn results_come_at_the_end_and_bad_options_are_errors() {
    let mut run = Minimizer::without_objective()
        .budget(50)
        .ask_tell(&[1.0])
        .unwrap();
    assert_eq!(run.best(), None);
    assert_eq!(run.result(), None);
    let ask = run.ask().unwrap().unwrap();
    let values = evaluate_elsewhere(ask, |x, _| x[0] * x[0]);
    run.tell(&values).unwrap();
    let (x, fun) = run.best().unwrap();
    assert_eq!(fun, values.iter().copied().fold(f64::INFINITY, f64::min));
    assert_eq!(x[0] * x[0], fun);
    assert_eq!(
        run.finish(),
        Err(Error::Unfinished {
            evaluations: values.len(),
            budget: 50
        })
    );
    // The options are checked where the run is made, as `run` checks them.
    let m = Minimizer::without_objective;
    assert_eq!(m().ask_tell(&[]).unwrap_err(), Error::EmptyTheta);
    assert!(matches!(
        m().budget(0).ask_tell(&[1.0]),
        Err(Error::InvalidParameter { name: "budget", .. })
    ));
    assert_eq!(
        m().strategy(Strategy::Paper {
            samples: 3,
            lr: 0.1,
            sigma0: 1.0
        })
        .ask_tell(&[1.0])
        .unwrap_err(),
        Error::OddSamples(3)
    );
    let opt = || Optimizer::new(Adam::new(0.1).unwrap(), Annealer::constant(0.2, 3).unwrap());
    assert_eq!(
        opt()
            .ask_tell(PlateauFreeGradient::without_objective().samples(3), &[1.0])
            .unwrap_err(),
        Error::OddSamples(3)
    );
    assert!(matches!(
        opt().ask_tell(PlateauFreeGradient::without_objective(), &[f64::NAN]),
        Err(Error::NonFiniteTheta { index: 0, .. })
    ));
}

#[test]
fn a_paper_budget_too_small_for_an_iteration_asks_for_the_start_alone() {
    let mut run = Minimizer::without_objective()
        .budget(4)
        .strategy(PAPER)
        .target(1.0)
        .ask_tell(&[0.25, 0.5])
        .unwrap();
    let ask = run.ask().unwrap().unwrap();
    assert_eq!(ask.points().as_flat(), &[0.25, 0.5]);
    assert_eq!(ask.seeds(), &[0]);
    assert_eq!(
        run.tell(&[0.5, 0.5]),
        Err(Error::TellCount {
            expected: 1,
            got: 2
        })
    );
    run.tell(&[0.5]).unwrap();
    let best = run.finish().unwrap();
    assert_eq!((best.fun, best.evaluations, best.iterations), (0.5, 1, 0));
    assert_eq!(best.stop, Stop::Target);
    let called = Minimizer::new(|x: &[f64]| x[0] + x[1] - 0.25)
        .budget(4)
        .strategy(PAPER)
        .target(1.0)
        .run(&[0.25, 0.5])
        .unwrap();
    assert_eq!(called, best);
}

/// The paper's loop stops at its target as the adaptive search does: after the estimate whose
/// points first reach it, with no final evaluation and no polish; the callback form and ask
/// and tell stop at the same evaluation.
#[test]
fn the_paper_loop_stops_after_the_estimate_that_reaches_the_target() {
    let f = |x: &[f64]| (x[0] - 1.0).powi(2) + (x[1] + 0.5).powi(2);
    let target = 0.05;
    for polish in [0.0, 0.5] {
        let mut run = Minimizer::without_objective()
            .budget(2002)
            .seed(4)
            .strategy(PAPER)
            .polish(polish)
            .target(target)
            .ask_tell(&[0.0, 0.0])
            .unwrap();
        let mut first_reached = None;
        while let Some(ask) = run.ask().unwrap() {
            let values: Vec<f64> = ask.iter().map(|(x, _)| f(x)).collect();
            let reached = values.iter().any(|&v| v <= target);
            run.tell(&values).unwrap();
            if reached && first_reached.is_none() {
                first_reached = Some(run.evaluations());
                assert!(run.is_done(), "the run goes on past its target");
            }
        }
        let told = run.finish().unwrap();
        assert_eq!(told.stop, Stop::Target, "{told:?}");
        assert!(told.fun <= target, "{told:?}");
        assert_eq!(Some(told.evaluations), first_reached);
        // The start (f = 1.25, above the target), then whole estimates of 4 points.
        assert_eq!(told.evaluations, 1 + 4 * told.iterations, "{told:?}");
        assert!(told.evaluations < 2002 / 4, "{told:?}");
        assert_eq!(f(&told.x), told.fun);
        let called = Minimizer::new(f)
            .budget(2002)
            .seed(4)
            .strategy(PAPER)
            .polish(polish)
            .target(target)
            .run(&[0.0, 0.0]);
        assert_eq!(called.as_ref(), Ok(&told), "polish {polish}");
    }
}
