//! Discrete coordinates (`Minimizer::steps`): every point handed to `f` and the result on
//! the grid and inside the box, the ask-and-tell run the same as the callback form, and bad
//! steps refused with an error.

use std::cell::RefCell;

use plateau_free::{run::Strategy, Error, Minimizer};

/// Whether `v` is a multiple of the step `s` (any `v` for a continuous coordinate).
fn on_grid(v: f64, s: f64) -> bool {
    s == 0.0 || (v / s).round() * s == v
}

/// Runs `m` from `x0`, recording every point handed to `f`.
fn recorded(
    m: &Minimizer<plateau_free::objective::NoObjective>,
    f: impl Fn(&[f64]) -> f64,
    x0: &[f64],
) -> (plateau_free::Minimum, Vec<Vec<f64>>) {
    let seen = RefCell::new(Vec::new());
    let mut run = m.ask_tell(x0).unwrap();
    while let Some(ask) = run.ask().unwrap() {
        let values: Vec<f64> = ask
            .iter()
            .map(|(x, _)| {
                seen.borrow_mut().push(x.to_vec());
                f(x)
            })
            .collect();
        run.tell(&values).unwrap();
    }
    (run.finish().unwrap(), seen.into_inner())
}

/// A mixed problem: an ellipsoid whose optimum is off the grid on the discrete coordinates.
fn mixed(x: &[f64]) -> f64 {
    x.iter()
        .enumerate()
        .map(|(i, v)| 10f64.powi(i as i32 % 3) * (v - 0.3 - i as f64).powi(2))
        .sum()
}

#[test]
fn every_point_and_the_result_are_on_the_grid_inside_the_box() {
    let steps = vec![1.0, 0.0, 0.5, 1.0, 0.25, 0.0];
    let (lo, hi) = (vec![-2.6; 6], vec![4.4, 5.0, 4.4, 2.5, 9.0, 9.0]);
    let m = Minimizer::without_objective()
        .steps(steps.clone())
        .bounds(lo.clone(), hi.clone())
        .budget(3000)
        .seed(4);
    let (best, seen) = recorded(&m, mixed, &[0.7; 6]);
    assert_eq!(seen.len(), best.evaluations);
    for x in seen.iter().chain([&best.x]) {
        for i in 0..6 {
            assert!(on_grid(x[i], steps[i]), "{x:?}");
            assert!(lo[i] <= x[i] && x[i] <= hi[i], "{x:?}");
        }
    }
    // The start, rounded, is evaluated first; the box holds -2, ..., 4 on coordinate 0.
    assert_eq!(seen[0], vec![1.0, 0.7, 0.5, 1.0, 0.75, 0.7]);
    // The best grid point: coordinate 3's optimum 3.3 is above its bound 2.5, so 2.
    assert_eq!(&best.x[..1], &[0.0]);
    assert_eq!(best.x[2], 2.5);
    assert_eq!(best.x[3], 2.0);
    assert_eq!(best.x[4], 4.25);
    assert!(
        (best.x[1] - 1.3).abs() < 1e-3 && (best.x[5] - 5.3).abs() < 1e-3,
        "{best:?}"
    );
}

#[test]
fn the_ask_and_tell_run_is_the_callback_form() {
    let m = Minimizer::without_objective()
        .steps(vec![1.0, 0.0, 1.0])
        .budget(600)
        .seed(9);
    let (told, _) = recorded(&m, mixed, &[2.2, -1.0, 0.4]);
    let run = Minimizer::new(mixed)
        .steps(vec![1.0, 0.0, 1.0])
        .budget(600)
        .seed(9)
        .run(&[2.2, -1.0, 0.4])
        .unwrap();
    assert_eq!(told, run);
}

#[test]
fn an_integer_ellipsoid_is_solved_on_the_grid() {
    // The rounding inside f too (a staircase for an undeclared run): the result is the
    // integer optimum itself, not a point of its cell.
    let n = 10;
    let f = |x: &[f64]| {
        x.iter()
            .enumerate()
            .map(|(i, v)| 10f64.powf(3.0 * i as f64 / (n - 1) as f64) * (v.round() - 3.0).powi(2))
            .sum::<f64>()
    };
    let (lo, hi) = (vec![-10.0; n], vec![10.0; n]);
    let declared = Minimizer::new(f)
        .steps(vec![1.0; n])
        .bounds(lo, hi)
        .budget(4000)
        .seed(1)
        .run(&vec![-7.0; n])
        .unwrap();
    assert_eq!(declared.fun, 0.0, "{declared:?}");
    assert_eq!(declared.x, vec![3.0; n]);
}

#[test]
fn dimension_one_and_huge_steps() {
    let f = |x: &[f64]| (x[0] - 7.2).abs();
    let one = Minimizer::new(f)
        .steps(vec![2.0])
        .budget(300)
        .run(&[0.0])
        .unwrap();
    assert_eq!(one.x, vec![8.0]);
    // A step larger than every coordinate: the grid is 0 and +-1e300 (and the box holds 0).
    let huge = Minimizer::new(f)
        .steps(vec![1e300])
        .bounds(vec![-5.0], vec![50.0])
        .budget(200)
        .run(&[3.0])
        .unwrap();
    assert_eq!(huge.x, vec![0.0]);
    // A coordinate beyond 2^52 steps is left as it is: no overflow, no panic.
    let far = Minimizer::new(|x: &[f64]| x[0].abs())
        .steps(vec![1e-300])
        .budget(100)
        .run(&[1e10])
        .unwrap();
    assert!(far.fun.is_finite() && far.fun <= 1e10);
}

#[test]
fn bad_steps_are_errors() {
    let run = |steps: Vec<f64>| {
        Minimizer::without_objective()
            .steps(steps)
            .bounds(vec![0.2, -1.0], vec![0.8, 1.0])
            .ask_tell(&[0.5, 0.0])
    };
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        let e = run(vec![0.0, bad]).unwrap_err();
        assert!(
            matches!(e, Error::InvalidParameter { name: "steps", .. }),
            "{e}"
        );
    }
    let e = run(vec![1.0]).unwrap_err();
    assert!(
        matches!(
            e,
            Error::LengthMismatch {
                what: "steps",
                expected: 2,
                got: 1
            }
        ),
        "{e}"
    );
    // [0.2, 0.8] holds no integer.
    let e = run(vec![1.0, 0.0]).unwrap_err();
    assert!(e.to_string().contains("no grid point"), "{e}");
    assert!(run(vec![0.1, 1.0]).is_ok());
    let paper = Strategy::Paper {
        samples: 2,
        lr: 0.1,
        sigma0: 0.5,
    };
    let e = Minimizer::without_objective()
        .steps(vec![1.0])
        .strategy(paper)
        .budget(100)
        .ask_tell(&[0.0])
        .unwrap_err();
    assert!(e.to_string().contains("Strategy::Adaptive"), "{e}");
}

#[cfg(feature = "serde")]
#[test]
fn a_saved_run_with_steps_goes_on_bit_for_bit() {
    let m = Minimizer::without_objective()
        .steps(vec![1.0, 0.0, 0.5])
        .bounds(vec![-3.0; 3], vec![3.0; 3])
        .budget(500)
        .seed(2);
    let mut run = m.ask_tell(&[1.0, 1.0, 1.0]).unwrap();
    for _ in 0..12 {
        let ask = run.ask().unwrap().unwrap();
        let values: Vec<f64> = ask.iter().map(|(x, _)| mixed(x)).collect();
        run.tell(&values).unwrap();
    }
    let saved = serde_json::to_string(&run).unwrap();
    let mut run: plateau_free::AskTell = serde_json::from_str(&saved).unwrap();
    while let Some(ask) = run.ask().unwrap() {
        let values: Vec<f64> = ask.iter().map(|(x, _)| mixed(x)).collect();
        run.tell(&values).unwrap();
    }
    assert_eq!(
        run.finish().unwrap(),
        recorded(&m, mixed, &[1.0, 1.0, 1.0]).0
    );
}

/// A linear slope on integers whose minimiser is the box's corner `hi`, with one continuous
/// coordinate: the search reaches the corner exactly (a clamped discrete coordinate stalled on
/// a face before the others reached theirs), every point in the box and on the grid.
#[test]
fn an_integer_slope_reaches_the_box_corner() {
    let n = 20;
    let mut steps = vec![1.0; n];
    steps[n - 1] = 0.0;
    let (lo, hi) = (vec![-5.0; n], vec![5.0; n]);
    let slope = |x: &[f64]| {
        x.iter()
            .enumerate()
            .map(|(i, v)| -(1.0 + i as f64 / 4.0) * v)
            .sum::<f64>()
    };
    for seed in 0..3 {
        let m = Minimizer::without_objective()
            .steps(steps.clone())
            .bounds(lo.clone(), hi.clone())
            .budget(2000 * n)
            .target(slope(&hi))
            .seed(seed);
        let (best, seen) = recorded(&m, slope, &vec![0.0; n]);
        assert_eq!(best.x, hi, "seed {seed}: {best:?}");
        for x in &seen {
            for i in 0..n {
                assert!(
                    on_grid(x[i], steps[i]) && lo[i] <= x[i] && x[i] <= hi[i],
                    "{x:?}"
                );
            }
        }
    }
}

/// A bowl whose minimiser lies beyond the box on two integer coordinates: the result is on
/// their faces and at the bowl's optimum elsewhere; the ask-and-tell run is the callback form.
#[test]
fn an_integer_bowl_with_its_minimiser_on_a_face() {
    let target = [7.0, -9.0, 1.0, 0.4];
    let bowl = |x: &[f64]| {
        x.iter()
            .zip(&target)
            .map(|(v, t)| (v - t).powi(2))
            .sum::<f64>()
    };
    let steps = vec![1.0, 1.0, 1.0, 0.0];
    let (lo, hi) = (vec![-3.0; 4], vec![3.0; 4]);
    let m = Minimizer::without_objective()
        .steps(steps.clone())
        .bounds(lo.clone(), hi.clone())
        .budget(3000)
        .seed(5);
    let (best, _) = recorded(&m, bowl, &[0.0, 2.0, -2.0, 0.0]);
    assert_eq!(&best.x[..3], &[3.0, -3.0, 1.0], "{best:?}");
    assert!((best.x[3] - 0.4).abs() < 1e-4, "{best:?}");
    let run = Minimizer::new(bowl)
        .steps(steps)
        .bounds(lo, hi)
        .budget(3000)
        .seed(5)
        .run(&[0.0, 2.0, -2.0, 0.0])
        .unwrap();
    assert_eq!(best, run);
}
