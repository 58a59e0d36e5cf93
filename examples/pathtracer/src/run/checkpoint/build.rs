//! The build that writes a checkpoint (the executable's hash, part of the run's identity),
//! and the text of a checkpoint made fit for one line.

use std::fs;

/// The running executable's 64-bit FNV-1a, in hex; `"unknown"` if it could not be read (a
/// checkpoint of such a build is never resumed).
pub(crate) fn executable() -> String {
    executable_hash().map_or_else(|| "unknown".into(), |h| format!("{h:016x}"))
}

/// Text read from a checkpoint (or its parser's message, which quotes the file) made fit for
/// a one-line message: control characters (a line break, an escape) written as escapes, and
/// at most [`ONE_LINE_MAX`] characters, the middle cut (a parser's message ends with the line
/// and column).
///
/// ```
/// use pathtracer::run::checkpoint::one_line;
/// assert_eq!(one_line("unknown variant `ra\ndial`"), "unknown variant `ra\\ndial`");
/// assert_eq!(one_line(&"x".repeat(1000)).chars().count(), 241);
/// ```
pub fn one_line(text: &str) -> String {
    let mut escaped: Vec<char> = Vec::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() {
            escaped.extend(c.escape_default());
        } else {
            escaped.push(c);
        }
    }
    if escaped.len() <= ONE_LINE_MAX {
        return escaped.into_iter().collect();
    }
    let half = ONE_LINE_MAX / 2;
    let head: String = escaped[..half].iter().collect();
    let tail: String = escaped[escaped.len() - half..].iter().collect();
    format!("{head}…{tail}")
}

/// The most characters [`one_line`] keeps of a text.
pub const ONE_LINE_MAX: usize = 240;

/// A hash of the running executable (`None` if it cannot be read), computed once.
pub fn executable_hash() -> Option<u64> {
    static HASH: std::sync::OnceLock<Option<u64>> = std::sync::OnceLock::new();
    *HASH.get_or_init(|| {
        let exe = std::env::current_exe().ok()?;
        fs::read(exe).ok().map(|bytes| fnv1a(&bytes))
    })
}

/// 64-bit FNV-1a: stable across runs and Rust versions, unlike `DefaultHasher`.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}
