//! A run's state is a value: a `Minimizer`'s ask and tell, for every
//! method, serialised with serde at any point (after a tell, between an ask and its tell),
//! dropped and read back, goes on bit for bit as the uninterrupted run.
#![cfg(feature = "serde")]

use plateau_free::{
    objective::NoObjective,
    run::{Metric, Strategy},
    AskTell, Minimizer, Minimum,
};

/// A staircase with a plateau around the start: flat almost everywhere.
fn f(x: &[f64]) -> f64 {
    x.iter()
        .enumerate()
        .map(|(i, v)| ((v * 2.0).round() - i as f64).powi(2))
        .sum()
}

/// The methods: the adaptive search (free, and in a box with a target that never stops it), the paper's loop,
/// and the loop with its polish.
fn methods() -> Vec<(&'static str, Minimizer<NoObjective>)> {
    let paper = Strategy::Paper {
        samples: 8,
        lr: 0.05,
        sigma0: 0.5,
    };
    vec![
        (
            "adaptive",
            Minimizer::without_objective().budget(300).seed(5),
        ),
        (
            "adaptive-box",
            Minimizer::without_objective()
                .budget(300)
                .seed(6)
                .bounds(vec![-2.0, -1.0, -1.0], vec![2.0, 3.0, 0.5])
                .target(f64::NEG_INFINITY),
        ),
        (
            "adaptive-decoded",
            Minimizer::without_objective()
                .budget(300)
                .seed(9)
                .metric(Metric::Decoded),
        ),
        (
            "paper",
            Minimizer::without_objective()
                .budget(200)
                .seed(7)
                .strategy(paper),
        ),
        (
            "polished",
            Minimizer::without_objective()
                .budget(300)
                .seed(8)
                .strategy(paper)
                .polish(0.5),
        ),
    ]
}

/// Every asked point (bits) and the result: the run, interrupted after `k` tells (and, with
/// `mid_ask`, between the next ask and its tell) by a round trip through JSON.
fn run(m: &Minimizer<NoObjective>, k: Option<(usize, bool)>) -> (Vec<Vec<u64>>, Minimum) {
    let x0 = [0.3, -0.4, 0.1];
    let mut run = m.ask_tell(&x0).unwrap();
    let mut asked = Vec::new();
    let mut tells = 0;
    let round_trip = |run: AskTell| -> AskTell {
        let json = serde_json::to_string(&run).unwrap();
        drop(run);
        serde_json::from_str(&json).unwrap()
    };
    loop {
        if k == Some((tells, false)) {
            run = round_trip(run);
        }
        let Some(ask) = run.ask().unwrap() else { break };
        let bits: Vec<u64> = ask.points().iter().flatten().map(|v| v.to_bits()).collect();
        let seeds: Vec<u64> = ask.seeds().to_vec();
        let values: Vec<f64> = ask.points().iter().map(f).collect();
        asked.push(bits.into_iter().chain(seeds).collect());
        if k == Some((tells, true)) {
            run = round_trip(run);
        }
        run.tell(&values).unwrap();
        tells += 1;
    }
    (asked, run.finish().unwrap())
}

#[test]
fn every_method_resumes_bit_for_bit_from_json() {
    for (name, m) in methods() {
        let (asked, result) = run(&m, None);
        let tells = asked.len();
        assert!(tells > 10, "{name}: {tells} tells");
        let mut ks = vec![0, 1, 2, tells / 3, tells / 2, tells - 2, tells - 1, tells];
        ks.dedup();
        for k in ks {
            for mid_ask in [false, true] {
                if mid_ask && k == tells {
                    continue; // no ask after the last tell
                }
                let (a, r) = run(&m, Some((k, mid_ask)));
                assert_eq!(
                    a, asked,
                    "{name}: points after {k} tells (mid ask {mid_ask})"
                );
                assert_eq!(
                    r, result,
                    "{name}: result after {k} tells (mid ask {mid_ask})"
                );
                assert_eq!(r.fun.to_bits(), result.fun.to_bits());
                let xs = |m: &Minimum| m.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(xs(&r), xs(&result), "{name}: x after {k} tells");
            }
        }
    }
}

/// The polished run does reach its polish, and the paper's loop its final point: the
/// interruptions above cover both hand-overs.
#[test]
fn the_methods_cover_their_phases() {
    for (name, m) in methods() {
        let (_, r) = run(&m, None);
        match name {
            "polished" => assert!(r.evaluations > 150, "{name}: {r:?}"),
            _ => assert!(r.evaluations > 100, "{name}: {r:?}"),
        }
    }
}

/// A finished run is a value too: read back, it is done and finishes with the same result.
#[test]
fn a_finished_run_reads_back_finished() {
    let m = Minimizer::without_objective().budget(100).seed(1);
    let mut run = m.ask_tell(&[0.5, 0.5]).unwrap();
    while let Some(ask) = run.ask().unwrap() {
        let values: Vec<f64> = ask.points().iter().map(f).collect();
        run.tell(&values).unwrap();
    }
    let json = serde_json::to_string(&run).unwrap();
    let back: AskTell = serde_json::from_str(&json).unwrap();
    assert!(back.is_done());
    assert_eq!(back.finish().unwrap(), run.finish().unwrap());
}

/// Not a state: an error, not a panic.
#[test]
fn garbage_is_an_error() {
    assert!(serde_json::from_str::<AskTell>("{}").is_err());
    assert!(serde_json::from_str::<AskTell>("[1, 2]").is_err());
}

/// The paper's loop alone ([`plateau_free::PaperAskTell`]) is a value too, mid-iteration
/// included.
#[test]
fn the_papers_loop_resumes_bit_for_bit() {
    use plateau_free::{Adam, Annealer, Optimizer, PaperAskTell, PlateauFreeGradient};
    let run_to = |cut: Option<usize>| {
        let opt = Optimizer::new(Adam::new(0.05).unwrap(), Annealer::paper(0.5, 30).unwrap());
        let grad = PlateauFreeGradient::without_objective().samples(6).seed(2);
        let mut run = opt.ask_tell(grad, &[0.3, -0.2]).unwrap();
        let mut asks = 0;
        while let Some(ask) = run.ask().unwrap() {
            let values: Vec<f64> = ask.points().iter().map(f).collect();
            if cut == Some(asks) {
                let json = serde_json::to_string(&run).unwrap();
                run = serde_json::from_str::<PaperAskTell>(&json).unwrap();
            }
            run.tell(&values).unwrap();
            asks += 1;
        }
        run.finish()
    };
    let whole = run_to(None);
    for cut in [0, 1, 15, 29] {
        assert_eq!(run_to(Some(cut)), whole, "cut after {cut} asks");
    }
}

/// A state whose vectors do not have the run's dimension is refused when read, naming what
/// is wrong, instead of panicking at a later ask or tell: every array of numbers of a saved
/// run (every method, mid ask), one number longer or shorter, is refused or runs to its end.
#[test]
fn a_state_of_the_wrong_dimension_is_an_error() {
    use serde_json::Value;
    let paper = Strategy::Paper {
        samples: 4,
        lr: 0.05,
        sigma0: 0.5,
    };
    for (m, k) in [
        (Minimizer::without_objective().budget(100).seed(1), 3),
        (
            Minimizer::without_objective()
                .budget(100)
                .seed(1)
                .strategy(paper),
            3,
        ),
        (
            Minimizer::without_objective()
                .budget(100)
                .seed(1)
                .strategy(paper)
                .polish(0.5),
            16,
        ),
    ] {
        let mut run = m.ask_tell(&[0.5, 0.5]).unwrap();
        for _ in 0..k {
            let ask = run.ask().unwrap().unwrap();
            let values: Vec<f64> = ask.points().iter().map(f).collect();
            run.tell(&values).unwrap();
        }
        // Mid ask: the asked points are saved too.
        let ask = run.ask().unwrap().unwrap();
        let pending: Vec<f64> = ask.points().iter().map(f).collect();
        let json = serde_json::to_value(&run).unwrap();
        assert!(serde_json::from_value::<AskTell>(json.clone()).is_ok());
        // Every array of numbers, one at a time, one number longer and one shorter.
        let mut paths = Vec::new();
        number_arrays(&json, &mut Vec::new(), &mut paths);
        assert!(paths.len() > 5, "{paths:?}");
        let mut panics = Vec::new();
        for (path, longer) in paths.iter().flat_map(|p| [(p, true), (p, false)]) {
            let mut bad = json.clone();
            let mut at = &mut bad;
            for key in path {
                at = match key {
                    Key::Field(f) => &mut at[f.as_str()],
                    Key::Index(i) => &mut at[*i],
                };
            }
            let Value::Array(items) = at else {
                unreachable!()
            };
            if longer {
                items.push(Value::from(0.25));
            } else {
                items.pop();
            }
            // Either refused, or a state that runs to its end without a panic (arrays that
            // are scratch space or records, whose length the run does not depend on).
            let Ok(mut back) = serde_json::from_value::<AskTell>(bad) else {
                continue;
            };
            let runs = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let _ = back.tell(&pending);
                while let Ok(Some(ask)) = back.ask() {
                    let values: Vec<f64> = ask.points().iter().map(f).collect();
                    if back.tell(&values).is_err() {
                        break;
                    }
                }
            }));
            if runs.is_err() {
                panics.push((path, longer));
            }
        }
        assert!(panics.is_empty(), "a changed array panics: {panics:?}");
    }
}

#[derive(Debug, Clone)]
enum Key {
    Field(String),
    Index(usize),
}

/// The paths of every array whose items are all numbers.
fn number_arrays(v: &serde_json::Value, path: &mut Vec<Key>, out: &mut Vec<Vec<Key>>) {
    use serde_json::Value;
    match v {
        Value::Array(items) if !items.is_empty() && items.iter().all(Value::is_number) => {
            out.push(path.clone());
        }
        Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                path.push(Key::Index(i));
                number_arrays(item, path, out);
                path.pop();
            }
        }
        Value::Object(map) => {
            for (k, item) in map {
                path.push(Key::Field(k.clone()));
                number_arrays(item, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}
