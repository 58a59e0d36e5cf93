//! What every command-line value may be: clap value parsers that refuse a bad value while
//! parsing, before any work, with one line naming the argument, the value and what is
//! allowed (clap adds the first two; these say the third), and exit code 2.

use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use plateau_free::Sampling;

use crate::tasks;

/// A whole number of at least `min` (a count: iterations, samples, spp, threads, ...).
pub(super) fn at_least<T>(min: T) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
{
    move |s: &str| {
        s.trim()
            .parse::<T>()
            .ok()
            .filter(|n| *n >= min)
            .ok_or_else(|| format!("allowed: a whole number >= {min}"))
    }
}

/// A whole number from `min` to `max`.
pub(super) fn between<T>(min: T, max: T) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
{
    move |s: &str| {
        s.trim()
            .parse::<T>()
            .ok()
            .filter(|n| *n >= min && *n <= max)
            .ok_or_else(|| format!("allowed: a whole number >= {min} and <= {max}"))
    }
}

/// A finite number.
pub(super) fn finite(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| "allowed: a finite number".into())
}

/// A finite number above zero (sigma0, learning rate, scale, step, seconds).
pub(super) fn positive(s: &str) -> Result<f64, String> {
    finite(s)
        .ok()
        .filter(|v| *v > 0.0)
        .ok_or_else(|| "allowed: a finite number > 0".into())
}

/// A resolution multiplier: above zero, at most [`MAX_SCALE`](crate::run::MAX_SCALE).
pub(super) fn scale(s: &str) -> Result<f64, String> {
    let max = crate::run::MAX_SCALE;
    finite(s)
        .ok()
        .filter(|v| *v > 0.0 && *v <= max)
        .ok_or_else(|| format!("allowed: a finite number > 0 and <= {max}"))
}

/// The stop rule's window, a fraction of the budget in (0, 1].
pub(super) fn fraction(s: &str) -> Result<f64, String> {
    finite(s)
        .ok()
        .filter(|v| *v > 0.0 && *v <= 1.0)
        .ok_or_else(|| "allowed: a fraction of the budget, > 0 and <= 1".into())
}

/// A share of the budget that may be nothing but not all of it (`--polish`).
pub(super) fn share(s: &str) -> Result<f64, String> {
    finite(s)
        .ok()
        .filter(|v| (0.0..1.0).contains(v))
        .ok_or_else(|| "allowed: a fraction of the budget, >= 0 and < 1".into())
}

/// A horizontal field of view in degrees: a pinhole camera sees less than half the sphere.
pub(super) fn fov(s: &str) -> Result<f64, String> {
    finite(s)
        .ok()
        .filter(|v| *v > 0.0 && *v < 180.0)
        .ok_or_else(|| "allowed: degrees, a number > 0 and < 180".into())
}

/// A sampler, by the library's one spelling of its name ([`Sampling`]'s `FromStr`).
pub(super) fn sampling(s: &str) -> Result<Sampling, String> {
    s.trim().parse::<Sampling>().map_err(|_| {
        let names: Vec<&str> = Sampling::ALL.iter().map(|m| m.name()).collect();
        format!("allowed: {}", names.join(", "))
    })
}

/// The name of a task.
pub(super) fn task(s: &str) -> Result<String, String> {
    let name = s.to_ascii_lowercase();
    if tasks::names().any(|n| n == name) {
        Ok(name)
    } else {
        Err(format!(
            "allowed: {}",
            tasks::names().collect::<Vec<_>>().join(", ")
        ))
    }
}

/// A directory to write into: new, or an existing directory (not a file), where this
/// process may write (checked before any work, so that a run does not end unable to write).
pub(super) fn out_dir(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if s.is_empty() || path.is_file() {
        return Err("allowed: a directory (new or existing), not a file".into());
    }
    writable_dir(&path)?;
    Ok(path)
}

/// A file to write (a page): not a directory, in a directory this process may write.
pub(super) fn out_file(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if s.is_empty() || path.is_dir() {
        return Err("allowed: a file name, not a directory".into());
    }
    writable_file(&path)?;
    Ok(path)
}

/// Refuses `path`, a directory to write into (made if missing), unless this process can
/// write there: a file is made and removed in the directory if it exists, else in its
/// nearest existing ancestor (which must be a directory). Nothing is left behind.
pub(super) fn writable_dir(path: &Path) -> Result<(), String> {
    let mut existing = path;
    while !existing.as_os_str().is_empty() && !existing.exists() {
        existing = existing.parent().unwrap_or(Path::new(""));
    }
    if existing.as_os_str().is_empty() {
        existing = Path::new(".");
    }
    if !existing.is_dir() {
        return Err(format!(
            "cannot write there: {} is not a directory",
            existing.display()
        ));
    }
    probe(existing)
}

/// Refuses `path`, a file to write, unless this process can write it: an existing file is
/// opened for appending (and left as it was), a new one's directory is probed as
/// [`writable_dir`] does.
fn writable_file(path: &Path) -> Result<(), String> {
    if path.is_file() {
        return std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map(drop)
            .map_err(|e| format!("cannot write there: {e}"));
    }
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => writable_dir(dir),
        _ => writable_dir(Path::new(".")),
    }
}

/// Makes and removes a file in the existing directory `dir`.
fn probe(dir: &Path) -> Result<(), String> {
    let name = format!(".pathtracer-write-test-{}", std::process::id());
    let file = dir.join(name);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&file)
        .map_err(|e| {
            let shown = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
            format!("cannot write there: {}: {e}", shown.display())
        })?;
    // The file was made: the directory is writable, whether or not it can be removed.
    let _ = std::fs::remove_file(&file);
    Ok(())
}

/// An existing directory of runs (to read).
pub(super) fn runs_dir(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if !s.is_empty() && path.is_dir() {
        Ok(path)
    } else {
        Err("allowed: an existing directory of runs (as `all --out DIR` leaves it)".into())
    }
}

/// The directory of a run to resume: an existing directory with a `checkpoint.json` (whether
/// the checkpoint is good is checked next, before any work).
pub(super) fn run_dir(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if !s.is_empty() && path.join(crate::run::checkpoint::FILE).is_file() {
        writable_dir(&path)?;
        Ok(path)
    } else {
        Err(format!(
            "allowed: the output directory of an earlier run, holding its {}",
            crate::run::checkpoint::FILE
        ))
    }
}

/// An image file to write: `.png` (sRGB) or `.exr` (linear), not a directory.
pub(super) fn image_file(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    let suffix = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match suffix.as_deref() {
        Some("png" | "exr") if !path.is_dir() => {
            writable_file(&path)?;
            Ok(path)
        }
        _ => Err("allowed: a file name ending in .png or .exr".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_refuse_zero_negatives_and_words() {
        let count = at_least(1usize);
        assert_eq!(count("3"), Ok(3));
        for bad in ["0", "-1", "2.5", "many", ""] {
            assert_eq!(
                count(bad),
                Err("allowed: a whole number >= 1".into()),
                "{bad}"
            );
        }
        assert_eq!(
            at_least(2usize)("1"),
            Err("allowed: a whole number >= 2".into())
        );
    }

    #[test]
    fn numbers_refuse_nan_infinities_and_out_of_range() {
        assert_eq!(positive("0.5"), Ok(0.5));
        for bad in ["0", "-1", "NaN", "inf", "-inf", "x"] {
            assert!(positive(bad).is_err(), "{bad}");
        }
        assert_eq!(finite("-2.5"), Ok(-2.5));
        assert!(finite("nan").is_err());
        assert_eq!(fov("60"), Ok(60.0));
        for bad in ["0", "180", "-30", "NaN", "1e9"] {
            assert!(fov(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn tasks_are_known_names() {
        assert_eq!(task("SHADOW"), Ok("shadow".into()));
        let err = task("nope").unwrap_err();
        assert!(
            err.contains("cup, shadow, occlusion, gi, sort, caustic, texture"),
            "{err}"
        );
    }

    #[test]
    fn outputs_refuse_files_and_unwritable_suffixes() {
        let file = std::env::temp_dir().join(format!("plateau-values-{}", std::process::id()));
        std::fs::write(&file, b"x").unwrap();
        let name = file.to_str().unwrap();
        assert!(out_dir(name).is_err());
        assert!(out_dir(std::env::temp_dir().to_str().unwrap()).is_ok());
        assert!(out_dir("a/new/dir").is_ok());
        assert!(image_file("a.png").is_ok() && image_file("b.EXR").is_ok());
        for bad in ["a.jpg", "a", "png", ""] {
            assert!(image_file(bad).is_err(), "{bad}");
        }
        std::fs::remove_file(&file).unwrap();
    }
}
