//! The test functions of the comparison: shifted and rotated versions of classic functions,
//! after the definitions of the BBOB testbed (Hansen, Finck, Ros and Auger, "Real-parameter
//! black-box optimization benchmarking 2009: noiseless functions definitions", INRIA RR-6829).
//! Every function has its optimum, value 0, at a random shift `x*` in `[-4, 4]^n`; the
//! rotation `R` is a random orthogonal matrix; both drawn from the instance's seed.

use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

/// The six functions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `sum z_i^2`, `z = x - x*`.
    Sphere,
    /// `sum 10^(6 i/(n-1)) z_i^2`, `z = R(x - x*)`: condition number 1e6.
    Ellipsoid,
    /// Rosenbrock's banana on `z = max(1, sqrt(n)/8) R(x - x*) + 1`.
    Rosenbrock,
    /// `10 (n - sum cos(2 pi z_i)) + sum z_i^2`, `z = R(x - x*)`: about 10^n local minima.
    Rastrigin,
    /// BBOB f7 without its second rotation: plateaus of a rounded, conditioned ellipsoid.
    StepEllipsoid,
    /// `sum floor(|z_i|)`, `z = R(x - x*)`: integer values, flat almost everywhere.
    SumOfFloors,
}

impl Kind {
    pub const ALL: [Kind; 6] = [
        Kind::Sphere,
        Kind::Ellipsoid,
        Kind::Rosenbrock,
        Kind::Rastrigin,
        Kind::StepEllipsoid,
        Kind::SumOfFloors,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Kind::Sphere => "sphere",
            Kind::Ellipsoid => "ellipsoid",
            Kind::Rosenbrock => "rosenbrock",
            Kind::Rastrigin => "rastrigin",
            Kind::StepEllipsoid => "step-ellipsoid",
            Kind::SumOfFloors => "sum-of-floors",
        }
    }

    /// The function group of the report.
    pub fn group(self) -> &'static str {
        match self {
            Kind::Sphere => "smooth",
            Kind::Ellipsoid | Kind::Rosenbrock => "ill-conditioned",
            Kind::Rastrigin => "multimodal",
            Kind::StepEllipsoid | Kind::SumOfFloors => "plateau",
        }
    }

    pub fn parse(s: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// One instance: a function, a dimension, a shift, a rotation, and the start point `x0`.
pub struct Problem {
    pub kind: Kind,
    pub n: usize,
    shift: Vec<f64>,
    /// Row-major `n x n`.
    rotation: Vec<f64>,
    pub x0: Vec<f64>,
}

impl Problem {
    pub fn new(kind: Kind, n: usize, seed: u64) -> Problem {
        // One stream per (function, dimension, seed); the start point depends on the seed only,
        // so every method starts from the same point.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(
            seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (n as u64) << 32 ^ kind as u64,
        );
        let shift = (0..n).map(|_| rng.random_range(-4.0..4.0)).collect();
        let rotation = random_rotation(n, &mut rng);
        let mut start = Xoshiro256PlusPlus::seed_from_u64(seed ^ (n as u64) << 40);
        let x0 = (0..n).map(|_| start.random_range(-4.0..4.0)).collect();
        Problem {
            kind,
            n,
            shift,
            rotation,
            x0,
        }
    }

    fn rotate(&self, x: &[f64], scale: f64, z: &mut [f64]) {
        let n = self.n;
        let d: Vec<f64> = x.iter().zip(&self.shift).map(|(a, b)| a - b).collect();
        for (i, zi) in z.iter_mut().enumerate() {
            let row = &self.rotation[i * n..(i + 1) * n];
            *zi = scale * row.iter().zip(&d).map(|(r, v)| r * v).sum::<f64>();
        }
    }

    /// `f(x) - f(x*)`: 0 at the optimum.
    pub fn eval(&self, x: &[f64]) -> f64 {
        let n = self.n;
        let ramp = |i: usize| {
            if n > 1 {
                i as f64 / (n - 1) as f64
            } else {
                0.0
            }
        };
        let mut z = vec![0.0; n];
        match self.kind {
            Kind::Sphere => x
                .iter()
                .zip(&self.shift)
                .map(|(a, b)| (a - b) * (a - b))
                .sum(),
            Kind::Ellipsoid => {
                self.rotate(x, 1.0, &mut z);
                z.iter()
                    .enumerate()
                    .map(|(i, v)| 10f64.powf(6.0 * ramp(i)) * v * v)
                    .sum()
            }
            Kind::Rosenbrock => {
                self.rotate(x, (n as f64).sqrt().max(8.0) / 8.0, &mut z);
                z.iter_mut().for_each(|v| *v += 1.0);
                z.windows(2)
                    .map(|w| 100.0 * (w[0] * w[0] - w[1]).powi(2) + (w[0] - 1.0).powi(2))
                    .sum()
            }
            Kind::Rastrigin => {
                self.rotate(x, 1.0, &mut z);
                10.0 * (n as f64
                    - z.iter()
                        .map(|v| (2.0 * std::f64::consts::PI * v).cos())
                        .sum::<f64>())
                    + z.iter().map(|v| v * v).sum::<f64>()
            }
            Kind::StepEllipsoid => {
                self.rotate(x, 1.0, &mut z);
                // Lambda^10: coordinate i scaled by 10^(0.5 i/(n-1)).
                for (i, v) in z.iter_mut().enumerate() {
                    *v *= 10f64.powf(0.5 * ramp(i));
                }
                let rounded = z.iter().enumerate().map(|(i, &v)| {
                    let r = if v.abs() > 0.5 {
                        (0.5 + v).floor()
                    } else {
                        (0.5 + 10.0 * v).floor() / 10.0
                    };
                    10f64.powf(2.0 * ramp(i)) * r * r
                });
                0.1 * (z[0].abs() / 1e4).max(rounded.sum())
            }
            Kind::SumOfFloors => {
                self.rotate(x, 1.0, &mut z);
                z.iter().map(|v| v.abs().floor()).sum()
            }
        }
    }
}

impl Problem {
    /// The instance as text for `studies/peers/peers.py`, which evaluates the same
    /// functions in numpy: a line `kind n seed`, then one line each of the shift, the rotation
    /// (row-major), the start, and `checks` lines of a point followed by its value here (the
    /// harness refuses to run if its values differ). Floats print in Rust's shortest
    /// round-trip form, so Python reads back the very same bits.
    pub fn export(&self, seed: u64, checks: &[Vec<f64>]) -> String {
        let line = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x:e}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let mut out = format!(
            "{} {} {seed}\n{}\n{}\n{}\n",
            self.kind.name(),
            self.n,
            line(&self.shift),
            line(&self.rotation),
            line(&self.x0)
        );
        for x in checks {
            out.push_str(&format!("{} {:e}\n", line(x), self.eval(x)));
        }
        out
    }

    /// Points at which the export's values are checked: the start, the optimum, a point
    /// between them, and points off the axes at a few scales (so every branch of the step
    /// ellipsoid's rounding is crossed).
    pub fn check_points(&self, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xC0FFEE);
        let mut points = vec![
            self.x0.clone(),
            self.shift.clone(),
            self.x0
                .iter()
                .zip(&self.shift)
                .map(|(a, b)| a + 0.37 * (b - a))
                .collect(),
        ];
        for scale in [0.01, 0.3, 3.0] {
            points.push(
                self.shift
                    .iter()
                    .map(|b| b + scale * rng.random_range(-1.0..1.0))
                    .collect(),
            );
        }
        points
    }
}

/// A random orthogonal matrix: Gram-Schmidt on a Gaussian matrix (row-major).
fn random_rotation(n: usize, rng: &mut Xoshiro256PlusPlus) -> Vec<f64> {
    let mut m: Vec<f64> = (0..n * n).map(|_| StandardNormal.sample(rng)).collect();
    for i in 0..n {
        for j in 0..i {
            let dot: f64 = (0..n).map(|k| m[i * n + k] * m[j * n + k]).sum();
            for k in 0..n {
                m[i * n + k] -= dot * m[j * n + k];
            }
        }
        let norm = (0..n).map(|k| m[i * n + k].powi(2)).sum::<f64>().sqrt();
        for k in 0..n {
            m[i * n + k] /= norm;
        }
    }
    m
}
