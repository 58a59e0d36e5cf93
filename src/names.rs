//! Reading the names that [`Sampling`] prints: its [`FromStr`], whose error is
//! [`Error::UnknownName`]. Apart from `sampling.rs` because [`Error`] names a [`Sampling`]
//! ([`Error::OrthogonalUnsupported`]): the sampler's module does not depend on the errors,
//! so that the two do not import each other.

use std::str::FromStr;

use crate::error::Error;
use crate::sampling::Sampling;

impl FromStr for Sampling {
    type Err = Error;

    /// Reads `radial`, `per-coordinate` or `gaussian`, ignoring ASCII case.
    ///
    /// # Errors
    /// [`Error::UnknownName`] for any other text, naming it and the accepted spellings.
    fn from_str(text: &str) -> Result<Self, Error> {
        Sampling::ALL
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(text.trim()))
            .ok_or_else(|| Error::UnknownName {
                what: "sampling",
                value: text.to_owned(),
                allowed: "radial, per-coordinate, gaussian",
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_are_errors() {
        for s in Sampling::ALL {
            assert_eq!(s.to_string().parse::<Sampling>(), Ok(s));
            assert_eq!(s.name().to_uppercase().parse::<Sampling>(), Ok(s));
        }
        match "percoordinate".parse::<Sampling>() {
            Err(Error::UnknownName {
                what,
                value,
                allowed,
            }) => {
                assert_eq!((what, value.as_str()), ("sampling", "percoordinate"));
                assert!(allowed.contains("per-coordinate"));
            }
            other => panic!("{other:?}"),
        }
    }
}
