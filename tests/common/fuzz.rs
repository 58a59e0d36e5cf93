//! Helpers of the fuzz tests (`fuzz_*.rs`): objectives whose values are huge, subnormal, NaN,
//! infinite or panics, and strategies for extreme magnitudes and dimensions.

use proptest::prelude::*;

/// What the objective returns.
#[derive(Debug, Clone, Copy)]
pub enum Values {
    /// A steep linear function of the point times a scale (up to f64::MAX).
    Linear(f64),
    /// A step of height `scale` across `x0 = 0`.
    Step(f64),
    /// Pseudo-random values from the point's bits, each of them one of: huge, subnormal,
    /// zero, NaN, an infinity, ordinary.
    Chaos(u64),
    /// Always this value.
    Constant(f64),
    /// Panics on points with `x0 > 0`.
    Panic,
}

pub fn value(kind: Values, x: &[f64]) -> f64 {
    match kind {
        Values::Linear(scale) => scale * x.iter().take(4).sum::<f64>(),
        Values::Step(scale) => {
            if x[0] > 0.0 {
                scale
            } else {
                0.0
            }
        }
        Values::Chaos(salt) => {
            let h = plateau_free::seeding::mix(x[0].to_bits() ^ salt);
            match h % 8 {
                0 => f64::NAN,
                1 => f64::INFINITY,
                2 => -f64::MAX,
                3 => f64::MAX,
                4 => 5e-324,
                5 => 0.0,
                _ => (h >> 11) as f64 * 1e-10,
            }
        }
        Values::Constant(v) => v,
        Values::Panic => {
            if x[0] > 0.0 {
                panic!("fuzz: intended panic")
            }
            1.0
        }
    }
}

pub fn extreme() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-300i32..=300, 1.0f64..10.0).prop_map(|(e, m)| m * 10f64.powi(e)),
        Just(f64::MAX),
        Just(f64::MIN_POSITIVE),
        Just(5e-324),
        Just(1e-300),
        Just(1e300),
        0.01f64..10.0,
    ]
}

pub fn signed_extreme() -> impl Strategy<Value = f64> {
    (extreme(), any::<bool>()).prop_map(|(x, neg)| if neg { -x } else { x })
}

pub fn values() -> impl Strategy<Value = Values> {
    prop_oneof![
        signed_extreme().prop_map(Values::Linear),
        signed_extreme().prop_map(Values::Step),
        any::<u64>().prop_map(Values::Chaos),
        prop_oneof![
            signed_extreme(),
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(0.0)
        ]
        .prop_map(Values::Constant),
        Just(Values::Panic),
    ]
}

pub fn dim() -> impl Strategy<Value = usize> {
    prop_oneof![4 => 1usize..=8, 1 => 9usize..=300, 1 => Just(10_000)]
}

pub fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}
