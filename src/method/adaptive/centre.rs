//! Integer centring: what the update learns from a selected draw that left the mean's tread
//! on a discrete coordinate ([`crate::Minimizer::steps`]).
//!
//! The objective sees a discrete coordinate only through its grid point, so a draw that
//! rounded to a neighbouring tread says "that tread is better", not "this offset is": it
//! usually landed just past the tread's edge, half a step from the mean, because the spread
//! there is near its floor (`gaussian/floor.rs`). Learning from the offset as drawn moves the
//! mean to the edge, where the next generation's draws fall back onto the old tread as often
//! as onto the new one, and the step that improved `f` is taken half-way; the step-size path
//! sees half-length steps and shrinks the spread. Learning from the grid point instead
//! moves the mean onto the new tread, and the selected steps are whole treads. So each of the
//! `mu` best draws whose discrete coordinate rounds off the mean's tread is learnt from at
//! the grid point it was evaluated at (in the search's space: unfolded from the box); a draw
//! that stayed on the mean's tread, a continuous coordinate and the draws not selected are
//! learnt from as drawn. This is the integer centring of LB+IC-CMA-ES (Marty, Semet, Auger,
//! Hansen and Tran, PPSN 2024), without its bias correction (which lost over COCO's
//! `bbob-mixint`: `docs/integers.md`), reasoned from its description.

use std::borrow::Cow;

use nalgebra::DVector;

use super::fold;
use super::gaussian::SearchGaussian;
use crate::run::Options;

/// The offsets the update learns from: `ys` (the asked generation's, in units of `sigma`)
/// with the `mu` best draws' discrete coordinates that left the mean's tread moved to the
/// grid points evaluated. `points` are the evaluated points (rows of `dist.n`), `ranked`
/// their values as the search ranks them. Without steps, `ys` as they are (not copied).
pub(super) fn centred<'a>(
    ys: &'a [DVector<f64>],
    dist: &SearchGaussian,
    points: &[f64],
    ranked: &[f64],
    o: &Options,
) -> Cow<'a, [DVector<f64>]> {
    let Some(steps) = o.steps.as_deref() else {
        return Cow::Borrowed(ys);
    };
    let mut out = ys.to_vec();
    let n = dist.n;
    let tread = evaluated(dist.mean.as_slice(), o);
    let mut order: Vec<usize> = (0..ys.len()).collect();
    order.sort_by(|&a, &b| ranked[a].total_cmp(&ranked[b]));
    for &k in order.iter().take(dist.p.mu) {
        let point = &points[k * n..(k + 1) * n];
        for i in (0..n).filter(|&i| steps[i] > 0.0 && point[i] != tread[i]) {
            let drawn = match &o.bounds {
                Some((lo, hi)) => fold::unfold(point[i], lo[i], hi[i]),
                None => point[i],
            };
            out[k][i] = (drawn - dist.mean[i]) / dist.sigma;
        }
    }
    Cow::Owned(out)
}

/// The point the search would evaluate at `x`: its discrete coordinates folded into the box
/// and every coordinate on the grid (the mean's tread, for the mean).
fn evaluated(x: &[f64], o: &Options) -> Vec<f64> {
    let mut x = x.to_vec();
    if let Some(bounds) = &o.bounds {
        fold::fold_discrete(&mut x, bounds, o.steps.as_deref());
    }
    o.snap(&mut x);
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run at mean (0.3, 0.3, 0.3), sigma 0.5, four draws (two selected), the first two
    /// coordinates of step 1 and the third continuous, with `bounds` if given.
    fn setup(bounds: Option<(Vec<f64>, Vec<f64>)>) -> (SearchGaussian, Options) {
        let dist = SearchGaussian::new(&[0.3; 3], 0.5, &[1.0; 3], 4, true);
        let o = Options {
            steps: Some(vec![1.0, 1.0, 0.0]),
            bounds,
            ..Options::default()
        };
        (dist, o)
    }

    /// The draws' offsets and the points they were evaluated at.
    fn generation(dist: &SearchGaussian, o: &Options) -> (Vec<DVector<f64>>, Vec<f64>) {
        let ys = vec![
            DVector::from_vec(vec![0.5, 0.1, 0.9]), // coordinate 0 at 0.55: tread 1
            DVector::from_vec(vec![-0.2, -1.4, 0.2]), // coordinate 1 at -0.4: tread 0
            DVector::from_vec(vec![2.0, 2.0, 2.0]),
            DVector::from_vec(vec![-2.0, -2.0, -2.0]),
        ];
        let points = ys
            .iter()
            .flat_map(|y| evaluated(dist.point(y).as_slice(), o))
            .collect();
        (ys, points)
    }

    #[test]
    fn a_selected_draw_off_the_mean_tread_is_learnt_at_its_grid_point() {
        let (dist, o) = setup(None);
        let (ys, points) = generation(&dist, &o);
        let out = centred(&ys, &dist, &points, &[1.0, 2.0, 3.0, 4.0], &o);
        // Draw 0 rounded to 1: learnt from (1 - 0.3) / 0.5; its other coordinates as drawn.
        assert!((out[0][0] - 1.4).abs() < 1e-15);
        assert_eq!((out[0][1], out[0][2]), (0.1, 0.9));
        // Draw 1 stayed on the mean's tread (0) in both discrete coordinates.
        assert_eq!(out[1], ys[1]);
        // Draws 2 and 3 were not selected.
        assert_eq!((&out[2], &out[3]), (&ys[2], &ys[3]));
    }

    #[test]
    fn the_ranks_decide_which_draws_are_centred_and_continuous_ones_never_are() {
        let (dist, o) = setup(None);
        let (ys, points) = generation(&dist, &o);
        let out = centred(&ys, &dist, &points, &[3.0, 4.0, 1.0, 2.0], &o);
        assert_eq!((&out[0], &out[1]), (&ys[0], &ys[1]));
        // Draw 2 at 1.3 (tread 1): 1.4 in coordinates 0 and 1; draw 3 at -0.7 (tread -1).
        assert!((out[2][0] - 1.4).abs() < 1e-15 && (out[2][1] - 1.4).abs() < 1e-15);
        assert!((out[3][0] + 2.6).abs() < 1e-15 && (out[3][1] + 2.6).abs() < 1e-15);
        assert_eq!((out[2][2], out[3][2]), (2.0, -2.0));
    }

    #[test]
    fn in_a_box_the_grid_point_is_unfolded_into_the_search_space() {
        let (dist, o) = setup(Some((vec![0.0; 3], vec![1.0; 3])));
        let (ys, points) = generation(&dist, &o);
        let out = centred(&ys, &dist, &points, &[3.0, 4.0, 1.0, 2.0], &o);
        // Draw 2 at 1.3 folds to 0.8 and draw 3 at -0.7 to 0.6 (reflected about the widened
        // box's ends): both were evaluated at 1, learnt from at 1 unfolded.
        assert_eq!((points[6], points[9]), (1.0, 1.0));
        let face = (fold::unfold(1.0, 0.0, 1.0) - 0.3) / 0.5;
        assert!((out[2][0] - face).abs() < 1e-15 && (out[3][0] - face).abs() < 1e-15);
        assert!(face > 1.4);
    }

    #[test]
    fn without_steps_the_offsets_are_kept() {
        let dist = SearchGaussian::new(&[0.3; 2], 0.5, &[1.0; 2], 4, true);
        let ys = vec![DVector::from_vec(vec![3.0, -3.0]); 4];
        let out = centred(
            &ys,
            &dist,
            &[1.8, -1.2].repeat(4),
            &[1.0; 4],
            &Options::default(),
        );
        assert!(matches!(out, Cow::Borrowed(_)));
        assert_eq!(&*out, &ys[..]);
    }
}
