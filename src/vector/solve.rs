//! The damped Gauss-Newton step on a sparse Jacobian: `(J^T J + lambda D) d = -J^T r`,
//! `D = diag(J^T J)` (Marquardt's scaling), by conjugate gradients with the diagonal as
//! preconditioner. Only products with `J` and `J^T` are formed, never `J^T J`.

use super::Sparsity;

/// `out = J x` (one value per output).
fn jac_times(s: &Sparsity, jac: &[f64], x: &[f64], out: &mut [f64]) {
    for (i, o) in out.iter_mut().enumerate() {
        let mut acc = 0.0;
        s.for_row(i, |k, j| acc += jac[k] * x[j]);
        *o = acc;
    }
}

/// `out = J^T y` (one value per parameter).
fn jac_t_times(s: &Sparsity, jac: &[f64], y: &[f64], out: &mut [f64]) {
    out.fill(0.0);
    for (i, &yi) in y.iter().enumerate() {
        if yi != 0.0 {
            s.for_row(i, |k, j| out[j] += jac[k] * yi);
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The step `d` minimising `|r + J d|^2 + lambda sum_j D_jj d_j^2`, at most `iterations`
/// conjugate-gradient steps (stopped when the residual of the normal equations falls below
/// `1e-10` of its start). A parameter no output depends on (`D_jj = 0`) does not move.
pub(crate) fn damped_step(
    s: &Sparsity,
    jac: &[f64],
    r: &[f64],
    lambda: f64,
    iterations: usize,
) -> Vec<f64> {
    let n = s.params();
    let mut diag = vec![0.0; n];
    for i in 0..s.outputs() {
        s.for_row(i, |k, j| diag[j] += jac[k] * jac[k]);
    }
    // A parameter with no (or a vanishing) column is held: its diagonal is replaced by a
    // tiny multiple of the largest, so the system stays positive definite and the
    // right-hand side, zero there, keeps it at zero.
    let largest = diag.iter().fold(0.0f64, |a, &b| a.max(b));
    let floor = if largest > 0.0 { largest * 1e-12 } else { 1.0 };
    let precond: Vec<f64> = diag
        .iter()
        .map(|&d| 1.0 / ((1.0 + lambda) * d.max(floor)))
        .collect();
    let mut b = vec![0.0; n];
    jac_t_times(s, jac, r, &mut b);
    b.iter_mut().for_each(|v| *v = -*v);
    let mut x = vec![0.0; n];
    let mut res = b.clone();
    let mut z: Vec<f64> = res.iter().zip(&precond).map(|(a, p)| a * p).collect();
    let mut p = z.clone();
    let mut rz = dot(&res, &z);
    let stop = 1e-20 * dot(&b, &b);
    let (mut jp, mut ap) = (vec![0.0; s.outputs()], vec![0.0; n]);
    for _ in 0..iterations {
        if dot(&res, &res) <= stop || rz <= 0.0 {
            break;
        }
        jac_times(s, jac, &p, &mut jp);
        jac_t_times(s, jac, &jp, &mut ap);
        for j in 0..n {
            ap[j] += lambda * diag[j].max(floor) * p[j];
        }
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        for j in 0..n {
            x[j] += alpha * p[j];
            res[j] -= alpha * ap[j];
        }
        for j in 0..n {
            z[j] = res[j] * precond[j];
        }
        let rz_next = dot(&res, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for j in 0..n {
            p[j] = z[j] + beta * p[j];
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small dense least-squares problem: the undamped step solves the normal equations.
    #[test]
    fn undamped_step_solves_the_normal_equations() {
        let s = Sparsity::dense(3, 2).unwrap();
        let jac = [1.0, 2.0, 0.5, -1.0, 3.0, 1.0];
        let r = [1.0, -2.0, 0.5];
        let d = damped_step(&s, &jac, &r, 0.0, 50);
        // Residual of the normal equations J^T (J d + r) = 0.
        let mut jd = [0.0; 3];
        jac_times(&s, &jac, &d, &mut jd);
        let e: Vec<f64> = jd.iter().zip(&r).map(|(a, b)| a + b).collect();
        let mut g = [0.0; 2];
        jac_t_times(&s, &jac, &e, &mut g);
        assert!(g.iter().all(|v| v.abs() < 1e-12), "{g:?}");
    }

    /// Damping shortens the step, and a parameter with no output stays put.
    #[test]
    fn damping_shortens_and_unused_parameters_hold() {
        let s = Sparsity::from_pairs(2, 3, &[(0, 0), (1, 1)]).unwrap();
        let jac = [2.0, 1.0];
        let r = [1.0, 1.0];
        let d0 = damped_step(&s, &jac, &r, 0.0, 10);
        assert!((d0[0] + 0.5).abs() < 1e-12 && (d0[1] + 1.0).abs() < 1e-12);
        assert_eq!(d0[2], 0.0);
        let d1 = damped_step(&s, &jac, &r, 1.0, 10);
        assert!((d1[0] + 0.25).abs() < 1e-12 && (d1[1] + 0.5).abs() < 1e-12);
    }
}
