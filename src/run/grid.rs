//! Discrete coordinates ([`crate::Minimizer::steps`]): a step per coordinate, 0 for a
//! continuous one, `s > 0` for the grid `{k s : k integer}` (`s = 1`: the integers). The
//! checks of the steps against the dimension and the box, and the rounding of a point onto
//! the grid inside the box, written once for the start, every asked point and the result.

use crate::error::Error;

/// Beyond this many steps from zero, a float's own spacing is at least the step: every
/// float there is already as near the grid as floats can be, and the point is left as is.
const LARGEST_MULTIPLE: f64 = 4_503_599_627_370_496.0; // 2^52

/// Checks `steps` against the dimension `n` and the box: one per coordinate, each finite and
/// `>= 0`, and on a bounded coordinate at least one grid point inside its bounds.
pub(crate) fn check(
    steps: &[f64],
    n: usize,
    bounds: Option<&(Vec<f64>, Vec<f64>)>,
) -> Result<(), Error> {
    crate::check::len("steps", steps.len(), n)?;
    for (i, &s) in steps.iter().enumerate() {
        if !(s.is_finite() && s >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "steps",
                value: s.into(),
                reason: "must be finite and >= 0 (0: a continuous coordinate)",
            });
        }
        let Some((lo, hi)) = bounds else { continue };
        if s > 0.0 && snap_one(lo[i], s, lo[i], hi[i]).is_none() {
            return Err(Error::InvalidParameter {
                name: "steps",
                value: s.into(),
                reason: "leaves no grid point k * step between a coordinate's bounds",
            });
        }
    }
    Ok(())
}

/// Rounds `x` onto the grid inside the box: each coordinate with a step to the nearest
/// multiple of it, then, if that left the box, to the nearest multiple inside it. (The box
/// was checked to hold one on each coordinate.)
pub(crate) fn snap(x: &mut [f64], steps: &[f64], bounds: Option<&(Vec<f64>, Vec<f64>)>) {
    for (i, (v, &s)) in x.iter_mut().zip(steps).enumerate() {
        if s == 0.0 {
            continue;
        }
        let (lo, hi) = bounds.map_or((f64::NEG_INFINITY, f64::INFINITY), |(l, h)| (l[i], h[i]));
        if let Some(on) = snap_one(*v, s, lo, hi) {
            *v = on;
        }
    }
}

/// The multiple of `s` nearest `v` inside `[lo, hi]`, `v` itself beyond [`LARGEST_MULTIPLE`]
/// steps, `None` when no multiple lies inside.
fn snap_one(v: f64, s: f64, lo: f64, hi: f64) -> Option<f64> {
    let k = (v / s).round();
    if k.is_nan() || k.abs() >= LARGEST_MULTIPLE {
        return Some(v);
    }
    let mut on = k * s;
    if on < lo {
        on = multiple(lo, s, f64::ceil);
    }
    if on > hi {
        on = multiple(hi, s, f64::floor);
    }
    // `+ 0.0` writes a rounded negative zero as zero.
    (lo..=hi).contains(&on).then_some(on + 0.0)
}

/// The multiple of `s` next to the bound `b`, on the side `side` rounds to (a bound beyond
/// [`LARGEST_MULTIPLE`] steps is its own grid point).
fn multiple(b: f64, s: f64, side: fn(f64) -> f64) -> f64 {
    let k = side(b / s);
    if k.abs() < LARGEST_MULTIPLE {
        k * s
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_to_the_nearest_multiple_inside_the_box() {
        let bounds = (vec![-0.4, 0.0, -1e9], vec![2.6, 1.0, 1e9]);
        let mut x = [-0.4, 0.74, 3.3];
        snap(&mut x, &[1.0, 0.25, 0.0], Some(&bounds));
        // -0.4 rounds to 0 (not -0), inside; 0.74 to 0.75; the continuous coordinate stays.
        assert_eq!(x, [0.0, 0.75, 3.3]);
        assert!(x[0].is_sign_positive());
        let mut x = [2.6];
        snap(&mut x, &[1.0], Some(&(vec![-0.4], vec![2.6])));
        // 3 is outside: the largest integer inside.
        assert_eq!(x, [2.0]);
        assert_eq!(snap_one(0.5, 1.0, 0.2, 0.8), None);
        assert_eq!(
            snap_one(1e300, 1e-300, f64::NEG_INFINITY, f64::INFINITY),
            Some(1e300)
        );
    }
}
