//! What a run's saved state needs beyond derived `Serialize`/`Deserialize` (the `serde`
//! feature): numbers that may be infinite or NaN (the best value before the first tell, a
//! box's open sides, an overflowed point) written so that JSON keeps them (serde_json
//! writes them as `null` and cannot read that back), and the one error that ends a run.

use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;

use crate::error::Error;

/// An `f64` that keeps its value through JSON: finite as a number, else `"inf"`, `"-inf"`
/// or `"nan"`.
#[derive(Clone, Copy)]
struct Float(f64);

impl Serialize for Float {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self.0 {
            v if v.is_finite() => s.serialize_f64(v),
            v if v.is_nan() => s.serialize_str("nan"),
            v if v > 0.0 => s.serialize_str("inf"),
            _ => s.serialize_str("-inf"),
        }
    }
}

impl<'de> Deserialize<'de> for Float {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Float, D::Error> {
        struct FloatVisitor;
        impl Visitor<'_> for FloatVisitor {
            type Value = Float;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number, \"inf\", \"-inf\" or \"nan\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Float, E> {
                Ok(Float(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Float, E> {
                Ok(Float(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Float, E> {
                Ok(Float(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Float, E> {
                match v {
                    "inf" => Ok(Float(f64::INFINITY)),
                    "-inf" => Ok(Float(f64::NEG_INFINITY)),
                    "nan" => Ok(Float(f64::NAN)),
                    _ => Err(E::invalid_value(de::Unexpected::Str(v), &self)),
                }
            }
        }
        d.deserialize_any(FloatVisitor)
    }
}

/// `#[serde(with = "float")]` for an `f64` that may not be finite.
pub(crate) mod float {
    use super::*;

    pub(crate) fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        Float(*v).serialize(s)
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Float::deserialize(d).map(|f| f.0)
    }
}

/// `#[serde(with = "floats")]` for a `Vec<f64>` whose entries may not be finite.
pub(crate) mod floats {
    use super::*;

    pub(crate) fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|&x| Float(x)))
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let v: Vec<Float> = Vec::deserialize(d)?;
        Ok(v.into_iter().map(|f| f.0).collect())
    }
}

/// `#[serde(with = "float_pairs")]` for the stop rule's marks `(evaluations, best)`, whose
/// best may be infinite before the first finite value.
pub(crate) mod float_pairs {
    use super::*;
    use std::collections::VecDeque;

    pub(crate) fn serialize<S: Serializer>(
        v: &VecDeque<(usize, f64)>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|&(e, b)| (e, Float(b))))
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<VecDeque<(usize, f64)>, D::Error> {
        let v: Vec<(usize, Float)> = Vec::deserialize(d)?;
        Ok(v.into_iter().map(|(e, b)| (e, b.0)).collect())
    }
}

/// `#[serde(with = "float_box")]` for a box `Option<(lower, upper)>`, whose sides may be
/// infinite.
pub(crate) mod float_box {
    use super::*;

    type Box = Option<(Vec<f64>, Vec<f64>)>;

    pub(crate) fn serialize<S: Serializer>(v: &Box, s: S) -> Result<S::Ok, S::Error> {
        let wrap = |side: &[f64]| side.iter().map(|&x| Float(x)).collect::<Vec<_>>();
        v.as_ref().map(|(lo, hi)| (wrap(lo), wrap(hi))).serialize(s)
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Box, D::Error> {
        let v: Option<(Vec<Float>, Vec<Float>)> = Option::deserialize(d)?;
        let unwrap = |side: Vec<Float>| side.into_iter().map(|f| f.0).collect::<Vec<_>>();
        Ok(v.map(|(lo, hi)| (unwrap(lo), unwrap(hi))))
    }
}

/// `#[serde(with = "failed")]` for the error that ends a run: only an overflowing point does
/// ([`Error::NonFinitePoint`]), so only that is kept; any other is written as `None`.
pub(crate) mod failed {
    use super::*;

    #[derive(Serialize, Deserialize)]
    struct Point {
        sample: usize,
        index: usize,
        #[serde(with = "super::float")]
        value: f64,
    }

    pub(crate) fn serialize<S: Serializer>(v: &Option<Error>, s: S) -> Result<S::Ok, S::Error> {
        let point = match v {
            Some(Error::NonFinitePoint {
                sample,
                index,
                value,
            }) => Some(Point {
                sample: *sample,
                index: *index,
                value: *value,
            }),
            _ => None,
        };
        point.serialize(s)
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Error>, D::Error> {
        let point: Option<Point> = Option::deserialize(d)?;
        Ok(point.map(|p| Error::NonFinitePoint {
            sample: p.sample,
            index: p.index,
            value: p.value,
        }))
    }
}

/// `#[serde(with = "float_option")]` for an `Option<f64>` that may not be finite.
pub(crate) mod float_option {
    use super::*;

    pub(crate) fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        v.map(Float).serialize(s)
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        Ok(Option::<Float>::deserialize(d)?.map(|f| f.0))
    }
}
