//! The adaptive search's start spread from what the caller gave: a box's widths (a quarter of
//! each coordinate's width), `sigma0_each` as given, `sigma0` over the box, else the default
//! from `x0`; and the errors of bad input.

use plateau_free::{Error, Minimizer, Objective, Stop};

/// The first generation's points (after the start), from an ask-and-tell run of `m` at `x0`.
fn first_generation<F>(m: Minimizer<F>, x0: &[f64]) -> Vec<Vec<f64>> {
    let mut run = m.ask_tell(x0).unwrap();
    let start = run.ask().unwrap().unwrap();
    assert_eq!(start.len(), 1, "the start is asked alone");
    run.tell(&[1.0]).unwrap();
    let ask = run.ask().unwrap().unwrap();
    ask.iter().map(|(x, _)| x.to_vec()).collect()
}

/// The root-mean-square offset of coordinate `i` from `x0` over `points`.
fn rms_offset(points: &[Vec<f64>], x0: &[f64], i: usize) -> f64 {
    let sum: f64 = points.iter().map(|x| (x[i] - x0[i]).powi(2)).sum();
    (sum / points.len() as f64).sqrt()
}

/// The spread a run reports when it ends at its start (a budget of one evaluation).
fn start_sigma<F: Objective>(m: Minimizer<F>, x0: &[f64]) -> f64 {
    let result = m.budget(1).run(x0).unwrap();
    assert_eq!(result.stop, Stop::Budget);
    result.sigma
}

#[test]
fn a_box_gives_a_quarter_of_each_width() {
    // Widths 0.1, 1, 10 and 100 (the diagonal metric at n = 4 is not used: the full one
    // starts diagonal, so each coordinate's spread is its own).
    let lo = vec![-0.05, 0.0, -5.0, 100.0];
    let hi = vec![0.05, 1.0, 5.0, 200.0];
    let x0 = [0.0, 0.5, 0.0, 150.0];
    let widths: Vec<f64> = lo.iter().zip(&hi).map(|(l, u)| u - l).collect();
    let mean = widths.iter().sum::<f64>() / 4.0;
    let f = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
    let boxed = || Minimizer::new(f).bounds(lo.clone(), hi.clone()).seed(3);
    assert!((start_sigma(boxed(), &x0) - 0.25 * mean).abs() <= 1e-12 * mean);
    // 4,000 draws from x0 at the box's centre: the box clips the draws beyond two spreads,
    // which leaves a root-mean-square offset of 0.959 spreads (of a standard normal clipped at
    // +-2); the sample's standard error is about 1.1 %.
    let points = first_generation(boxed().population(4000).budget(100_000), &x0);
    assert_eq!(points.len(), 4000);
    for (i, w) in widths.iter().enumerate() {
        let rms = rms_offset(&points, &x0, i);
        let want = 0.959 * 0.25 * w;
        assert!(
            (rms / want - 1.0).abs() < 0.04,
            "coordinate {i}: offset {rms}, a quarter of the width {want}"
        );
    }
}

#[test]
fn sigma0_over_a_box_keeps_the_widths_ratios_and_sigma0_each_is_as_given() {
    let f = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
    let x0 = [0.0, 0.0];
    // sigma0 sets the mean spread; the box's widths still set the ratios (1 : 10).
    let m = Minimizer::new(f)
        .bounds(vec![-1.0, -10.0], vec![1.0, 10.0])
        .sigma0(0.01)
        .population(4000)
        .budget(100_000)
        .seed(1);
    let points = first_generation(m, &x0);
    let (a, b) = (rms_offset(&points, &x0, 0), rms_offset(&points, &x0, 1));
    assert!((a / (0.01 * 2.0 / 11.0) - 1.0).abs() < 0.06, "{a}");
    assert!((b / (0.01 * 20.0 / 11.0) - 1.0).abs() < 0.06, "{b}");
    // sigma0_each: one spread per coordinate, as given, with or without a box.
    let m = Minimizer::new(f)
        .bounds(vec![-100.0; 2], vec![100.0; 2])
        .sigma0_each(vec![0.3, 3.0])
        .population(4000)
        .budget(100_000)
        .seed(2);
    let points = first_generation(m, &x0);
    assert!((rms_offset(&points, &x0, 0) / 0.3 - 1.0).abs() < 0.06);
    assert!((rms_offset(&points, &x0, 1) / 3.0 - 1.0).abs() < 0.06);
    // Nothing given: half the start's largest magnitude, at least 0.5.
    assert_eq!(start_sigma(Minimizer::new(f), &[0.1, -4.0]), 2.0);
    assert_eq!(start_sigma(Minimizer::new(f), &[0.1, 0.2]), 0.5);
    // A box open on every side gives no width: the default.
    let open = Minimizer::new(f).bounds(vec![f64::NEG_INFINITY; 2], vec![f64::INFINITY; 2]);
    assert_eq!(start_sigma(open, &[0.1, -4.0]), 2.0);
}

#[test]
fn bad_start_spreads_are_errors() {
    let f = |x: &[f64]| x[0] * x[0];
    fn err<F: Objective>(m: Minimizer<F>) -> Error {
        m.run(&[0.5, 0.5]).unwrap_err()
    }
    assert!(matches!(
        err(Minimizer::new(f).bounds(vec![1.0, 0.0], vec![0.0, 1.0])),
        Error::InvalidBounds { index: 0, .. }
    ));
    assert!(matches!(
        err(Minimizer::new(f).bounds(vec![0.0, f64::NAN], vec![1.0, 1.0])),
        Error::InvalidBounds { index: 1, .. }
    ));
    assert!(matches!(
        err(Minimizer::new(f).sigma0_each(vec![0.1, 0.0])),
        Error::InvalidParameter {
            name: "sigma0_each",
            ..
        }
    ));
    assert!(matches!(
        err(Minimizer::new(f).sigma0_each(vec![0.1])),
        Error::LengthMismatch { .. }
    ));
    assert!(matches!(
        err(Minimizer::new(f).sigma0_each(vec![0.1, 0.2]).sigma0(0.1)),
        Error::InvalidParameter {
            name: "sigma0_each",
            ..
        }
    ));
    assert!(matches!(
        err(Minimizer::new(f).sigma0(f64::NAN)),
        Error::InvalidParameter { name: "sigma0", .. }
    ));
}
