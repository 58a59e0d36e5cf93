//! The library's API as users of rand and glam expect it: names that parse and print with
//! one spelling (and every bad name an error that says which), configurations checked where they are made, `Debug` everywhere, serde
//! behind its feature, and the fast paths agreeing with the general ones bit for bit.

use plateau_free::baseline::{FiniteDifference, Spsa};
use plateau_free::seeding::{mix, stream_seed};
use plateau_free::{
    anneal::Schedule, error::ParameterValue, objective::Batch, objective::Points,
    objective::Seeded, run::History, Adam, Annealer, Error, Estimate, Optimizer,
    PlateauFreeGradient, Sampling,
};

fn linear(x: &[f64]) -> f64 {
    x.iter().enumerate().map(|(i, v)| (i + 1) as f64 * v).sum()
}

#[test]
fn sampling_names_have_one_spelling_each() {
    let names: Vec<String> = Sampling::ALL.iter().map(Sampling::to_string).collect();
    assert_eq!(names, ["radial", "per-coordinate", "gaussian"]);
    for s in Sampling::ALL {
        assert_eq!(s.to_string().parse::<Sampling>(), Ok(s));
        assert_eq!(s.to_string().to_uppercase().parse::<Sampling>(), Ok(s));
    }
    // The old CSV spelling is not a second name.
    let err = "percoordinate".parse::<Sampling>().unwrap_err();
    assert_eq!(
        err,
        Error::UnknownName {
            what: "sampling",
            value: "percoordinate".into(),
            allowed: "radial, per-coordinate, gaussian",
        }
    );
    let text = err.to_string();
    assert!(text.contains("\"percoordinate\""), "{text}");
    assert!(text.contains("radial, per-coordinate, gaussian"), "{text}");
}

#[test]
fn schedule_names_round_trip_and_name_bad_values() {
    for s in [
        Schedule::Constant,
        Schedule::WarmLinear { warmup: 0.5 },
        Schedule::WarmLinear { warmup: 0.3 },
        Schedule::WarmLinear { warmup: 0.125 },
        Schedule::WarmLinear { warmup: 0.0 },
        Schedule::Exponential,
        Schedule::Cosine,
    ] {
        assert_eq!(s.to_string().parse::<Schedule>(), Ok(s), "{s}");
    }
    assert_eq!(
        Schedule::WarmLinear { warmup: 0.5 }.to_string(),
        "warm-linear:0.5"
    );
    for bad in ["linear", "warm-linear", "warm-linear:x", ""] {
        match bad.parse::<Schedule>() {
            Err(Error::UnknownName { what, value, .. }) => {
                assert_eq!((what, value.as_str()), ("schedule", bad));
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
    assert!(matches!(
        "warm-linear:1".parse::<Schedule>(),
        Err(Error::InvalidParameter { name: "warmup", value, .. }) if value == ParameterValue::Float(1.0)
    ));
    let text = "geometric".parse::<Schedule>().unwrap_err().to_string();
    assert!(
        text.contains("\"geometric\"") && text.contains("cosine"),
        "{text}"
    );
    assert_eq!(
        "warm-linear:-0.1".parse::<Schedule>(),
        Err(Error::InvalidParameter {
            name: "warmup",
            value: ParameterValue::Float(-0.1),
            reason: "must be in [0, 1)"
        })
    );
}

#[test]
fn validate_reports_a_bad_configuration_where_it_is_made() {
    let est = |samples, antithetic, orthogonal, sampling| {
        PlateauFreeGradient::new(linear)
            .samples(samples)
            .antithetic(antithetic)
            .orthogonal(orthogonal)
            .sampling(sampling)
    };
    assert_eq!(
        est(0, true, false, Sampling::Radial).validate(),
        Err(Error::ZeroSamples)
    );
    assert_eq!(
        est(0, false, false, Sampling::Radial).validate(),
        Err(Error::ZeroSamples)
    );
    assert_eq!(
        est(5, true, false, Sampling::Gaussian).validate(),
        Err(Error::OddSamples(5))
    );
    assert_eq!(
        est(4, true, true, Sampling::PerCoordinate).validate(),
        Err(Error::OrthogonalUnsupported(Sampling::PerCoordinate))
    );
    assert_eq!(est(5, false, true, Sampling::Gaussian).validate(), Ok(()));
    assert_eq!(
        est(2, true, false, Sampling::PerCoordinate).validate(),
        Ok(())
    );
    // The estimate checks the same rules, and a rejected estimate is not counted.
    let mut bad = est(3, true, false, Sampling::Radial);
    assert_eq!(bad.estimate(&[1.0], 0.5), Err(Error::OddSamples(3)));
    assert_eq!(bad.estimates_made(), 0);
    // The shared checks: Adam and the annealer name the value that is wrong.
    assert_eq!(
        Adam::new(0.1).unwrap().betas(0.9, 1.5).unwrap_err(),
        Error::InvalidParameter {
            name: "beta2",
            value: ParameterValue::Float(1.5),
            reason: "must be in [0, 1)"
        }
    );
    assert_eq!(
        Annealer::paper(0.5, 0).unwrap_err(),
        Error::InvalidParameter {
            name: "iterations",
            value: ParameterValue::Integer(0),
            reason: "must be at least 1"
        }
    );
}

#[test]
fn every_public_type_has_debug() {
    let closure = |x: &[f64]| x[0];
    let est = PlateauFreeGradient::new(closure).samples(4).seed(9);
    let text = format!("{est:?}");
    for part in [
        "PlateauFreeGradient",
        "samples: 4",
        "seed: 9",
        "Radial",
        "objective",
    ] {
        assert!(text.contains(part), "{text}");
    }
    let fd = FiniteDifference::new(closure, 1e-3).unwrap();
    assert!(format!("{fd:?}").contains("step: 0.001"));
    assert!(format!("{:?}", Spsa::new(closure).seed(3)).contains("seed: 3"));
    assert!(format!("{:?}", Seeded(|x: &[f64], _s: u64| x[0])).starts_with("Seeded("));
    let batch = Batch(|_: Points<'_>, _: &[u64], _: &mut [f64]| {});
    assert!(format!("{batch:?}").starts_with("Batch("));
    let opt = Optimizer::new(Adam::new(0.1).unwrap(), Annealer::paper(0.5, 10).unwrap());
    assert!(format!("{opt:?}").contains("Annealer"));
    assert!(format!("{:?}", Points::new(&[1.0, 2.0], 1)).contains("dim: 1"));
    assert!(format!("{:?}", History::default()).contains("History"));
    assert!(format!("{:?}", Schedule::Cosine).contains("Cosine"));
}

#[test]
fn seeds_are_splitmix64() {
    // SplitMix64's published first outputs for the states 0 and 1 (one step each).
    assert_eq!(mix(0), 0xE220_A839_7B1D_CDAF);
    assert_eq!(mix(1), 0x910A_2DEC_8902_5CC1);
    let seeds: Vec<u64> = (0..64).map(|k| stream_seed(7, 3, k)).collect();
    let mut unique = seeds.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), seeds.len());
}

/// A scalar sigma takes a path of its own (no vector of spreads); it must give exactly the
/// bits of the same spread written out per coordinate, for every sampler and option.
#[test]
fn scalar_and_per_coordinate_spreads_agree_bit_for_bit() {
    for sampling in Sampling::ALL {
        for antithetic in [true, false] {
            for (n, samples) in [(1, 2), (7, 4), (300, 6), (40_000, 2)] {
                let make = || {
                    PlateauFreeGradient::new(Seeded(|x: &[f64], s: u64| {
                        (x[0] - x[x.len() - 1]).sin() + (s % 3) as f64
                    }))
                    .sampling(sampling)
                    .antithetic(antithetic)
                    .samples(samples)
                    .seed(11)
                };
                let theta: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).cos()).collect();
                let a: Estimate = make().estimate(&theta, 0.3).unwrap();
                let b = make().estimate_with_spreads(&theta, &vec![0.3; n]).unwrap();
                let bits =
                    |e: &Estimate| e.gradient.iter().map(|g| g.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a), bits(&b), "{sampling} {antithetic} n={n}");
                assert_eq!(a.mean_value.to_bits(), b.mean_value.to_bits());
            }
        }
    }
}

/// Finite points whose difference overflows take the exact check, which lets them pass:
/// the fast test of finiteness only ever sends a check down the slow path, never fails it.
#[test]
fn huge_finite_points_are_not_mistaken_for_overflow() {
    let mut passed_huge = false;
    for seed in 0..200 {
        let mut est = PlateauFreeGradient::new(|x: &[f64]| x[0].abs() * 1e-300).seed(seed);
        match est.estimate(&[0.0], 6e307) {
            // mean_value is |tau| * 1e-300: the points were +-|tau|.
            Ok(e) => passed_huge |= e.mean_value > 0.9e8,
            Err(Error::NonFinitePoint { value, .. }) => assert!(value.is_infinite()),
            Err(other) => panic!("{other:?}"),
        }
    }
    assert!(passed_huge, "no seed gave points above 9e307");
}

#[test]
fn a_non_finite_theta_is_named_and_not_counted() {
    let mut est = PlateauFreeGradient::new(linear).samples(4);
    for bad in [f64::NAN, f64::INFINITY] {
        let theta = [0.5, bad, 1.0];
        assert!(matches!(
            est.estimate(&theta, 0.1),
            Err(Error::NonFiniteTheta { index: 1, .. })
        ));
    }
    assert_eq!(est.estimates_made(), 0);
}

#[cfg(feature = "serde")]
#[test]
fn serde_round_trips_with_the_same_names() {
    assert_eq!(
        serde_json::to_string(&Sampling::PerCoordinate).unwrap(),
        "\"per-coordinate\""
    );
    for s in Sampling::ALL {
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(json, format!("\"{s}\""));
        assert_eq!(serde_json::from_str::<Sampling>(&json).unwrap(), s);
    }
    assert!(serde_json::from_str::<Sampling>("\"percoordinate\"").is_err());
    for s in [
        Schedule::Constant,
        Schedule::WarmLinear { warmup: 0.5 },
        Schedule::Cosine,
    ] {
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(
            serde_json::from_str::<Schedule>(&json).unwrap(),
            s,
            "{json}"
        );
    }
    let est = PlateauFreeGradient::new(linear)
        .samples(4)
        .seed(2)
        .estimate(&[0.25, -0.5], 0.3)
        .unwrap();
    let back: Estimate = serde_json::from_str(&serde_json::to_string(&est).unwrap()).unwrap();
    assert_eq!(back, est);
    let mut opt = Optimizer::new(Adam::new(0.05).unwrap(), Annealer::paper(0.5, 5).unwrap());
    let history = opt
        .minimize(&mut PlateauFreeGradient::new(linear), &[1.0])
        .unwrap();
    let back: History = serde_json::from_str(&serde_json::to_string(&history).unwrap()).unwrap();
    assert_eq!(back, history);
}
