//! The adaptive search's box. A continuous coordinate of a draw is clamped onto the box and the
//! search learns from the clamped offset, so a minimiser on a face is hit exactly by every draw
//! beyond it. A discrete coordinate ([`crate::Minimizer::steps`]) is folded into the box
//! instead, by a periodic map that is the identity well inside, quadratic within a margin of
//! each face and mirrored beyond (CMA-ES's boundary transform, reasoned from its description),
//! and the search learns from the draw as drawn. A clamped offset is short and biased inward:
//! with the mean on a face the spread along that coordinate shrinks (or grows) before the
//! other coordinates reach their faces, and on a grid the spread decides whether a draw leaves
//! its tread. A folded one has no such bias, and the rounding onto the grid puts every folded
//! value near a face exactly on the face's grid point.

use crate::run::Options;

/// The margin, in a coordinate's units, within which the map is quadratic: a twentieth of the
/// box's width, or of `1 + |bound|` on a coordinate bounded on one side only.
fn margin(lo: f64, hi: f64) -> f64 {
    if lo.is_finite() && hi.is_finite() {
        (hi - lo) / 20.0
    } else if lo.is_finite() {
        (1.0 + lo.abs()) / 20.0
    } else {
        (1.0 + hi.abs()) / 20.0
    }
}

/// `x` folded into `[lo, hi]` (an open side is not folded; a box of zero width is its point).
pub(super) fn fold(x: f64, lo: f64, hi: f64) -> f64 {
    if lo == hi {
        return lo;
    }
    if lo == f64::NEG_INFINITY && hi == f64::INFINITY || !x.is_finite() {
        return x;
    }
    let a = margin(lo, hi);
    let (low, high) = (lo - a, hi + a);
    // Onto [low, high] by reflection at its ends (periodic when both are finite).
    let z = if low.is_finite() && high.is_finite() {
        let r = (x - low).rem_euclid(2.0 * (high - low));
        low + if r > high - low {
            2.0 * (high - low) - r
        } else {
            r
        }
    } else if low.is_finite() && x < low {
        2.0 * low - x
    } else if high.is_finite() && x > high {
        2.0 * high - x
    } else {
        x
    };
    let y = if z < lo + a {
        lo + (z - low).powi(2) / (4.0 * a)
    } else if z > hi - a {
        hi - (high - z).powi(2) / (4.0 * a)
    } else {
        z
    };
    y.clamp(lo, hi)
}

/// A point of `[lo, hi]` (clamped onto it first) back in the search's space: the `x` nearest
/// the box that [`fold`] takes to it.
pub(super) fn unfold(y: f64, lo: f64, hi: f64) -> f64 {
    if lo >= hi || !y.is_finite() {
        return y;
    }
    let y = y.clamp(lo, hi);
    let a = margin(lo, hi);
    if y < lo + a {
        lo - a + (4.0 * a * (y - lo)).sqrt()
    } else if y > hi - a {
        hi + a - (4.0 * a * (hi - y)).sqrt()
    } else {
        y
    }
}

/// Whether coordinate `i` is folded (a discrete one) rather than clamped.
fn folded(steps: Option<&[f64]>, i: usize) -> bool {
    steps.is_some_and(|s| s[i] > 0.0)
}

/// The continuous coordinates of `x` clamped onto the box `(lo, hi)`; whether one moved.
pub(super) fn clamp_continuous(
    x: &mut [f64],
    (lo, hi): &(Vec<f64>, Vec<f64>),
    steps: Option<&[f64]>,
) -> bool {
    let mut moved = false;
    for (i, v) in x.iter_mut().enumerate() {
        if !folded(steps, i) {
            let c = v.clamp(lo[i], hi[i]);
            moved |= c != *v;
            *v = c;
        }
    }
    moved
}

/// The discrete coordinates of `x` folded into the box `(lo, hi)` ([`fold`]).
pub(super) fn fold_discrete(x: &mut [f64], (lo, hi): &(Vec<f64>, Vec<f64>), steps: Option<&[f64]>) {
    if steps.is_none() {
        return; // no discrete coordinate: no pass over the point
    }
    for (i, v) in x.iter_mut().enumerate() {
        if folded(steps, i) {
            *v = fold(*v, lo[i], hi[i]);
        }
    }
}

/// A point of the box in the search's space: its discrete coordinates unfolded ([`unfold`]).
pub(super) fn unfold_discrete(y: &[f64], o: &Options) -> Vec<f64> {
    let mut x = y.to_vec();
    if let Some((lo, hi)) = &o.bounds {
        for (i, v) in x.iter_mut().enumerate() {
            if folded(o.steps.as_deref(), i) {
                *v = unfold(*v, lo[i], hi[i]);
            }
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_inside_quadratic_at_faces_periodic_beyond() {
        assert_eq!(fold(0.5, 0.0, 1.0), 0.5);
        // The face is reached at one margin beyond it, with slope zero.
        assert_eq!(fold(-0.05, 0.0, 1.0), 0.0);
        assert_eq!(fold(1.05, 0.0, 1.0), 1.0);
        assert!((fold(-0.04, 0.0, 1.0) - 0.0005).abs() < 1e-15);
        // Mirrored about the face's far point, and periodic with twice the widened width.
        assert!((fold(-0.3, 0.0, 1.0) - 0.2).abs() < 1e-12);
        assert!((fold(0.3 + 2.2, 0.0, 1.0) - 0.3).abs() < 1e-12);
        for k in -400..400 {
            let x = k as f64 * 0.0137;
            let y = fold(x, -1.0, 2.0);
            assert!((-1.0..=2.0).contains(&y), "{x} -> {y}");
        }
    }

    #[test]
    fn unfold_inverts_fold_inside_the_box() {
        for k in 0..=100 {
            let y = k as f64 / 100.0;
            assert!((fold(unfold(y, 0.0, 1.0), 0.0, 1.0) - y).abs() < 1e-12);
        }
        assert_eq!(unfold(3.0, 0.0, 1.0), 1.05);
    }

    #[test]
    fn one_sided_and_open_boxes() {
        assert_eq!(fold(-7.0, f64::NEG_INFINITY, f64::INFINITY), -7.0);
        assert_eq!(fold(5.0, 0.0, f64::INFINITY), 5.0);
        assert!((fold(-1.0, 0.0, f64::INFINITY) - 0.9).abs() < 1e-12);
        assert_eq!(fold(-1.0, 2.0, 2.0), 2.0);
    }
}
