//! The checkpoint loader on random and damaged bytes: never a panic, always a clear error
//! that names the file (or, for a change that keeps the file valid, a checkpoint that passed
//! every check).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use pathtracer::run::{self, Checkpoint, Control};
use pathtracer::tasks;
use proptest::prelude::*;

/// A real checkpoint: the bytes of a short run of SHADOW's (made once).
fn good() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("plateau-ckpt-prop-{}", std::process::id()));
        let path = dir.join("checkpoint.json");
        let task = tasks::by_name("shadow").unwrap();
        let mut s = run::Settings::defaults(&task);
        s.iterations = 3;
        s.spp = 1;
        s.scale = Some(0.0625);
        let control = Control {
            checkpoint: Some(path.clone()),
            ..Control::default()
        };
        run::optimize_with(&task, &s, control).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        bytes
    })
}

fn name() -> PathBuf {
    Path::new("out/shadow/checkpoint.json").into()
}

/// Parses `bytes`; an error must name the file and be one line.
fn check(bytes: &[u8]) -> Result<(), TestCaseError> {
    if let Err(e) = Checkpoint::parse(bytes, &name()) {
        let message = e.to_string();
        prop_assert!(message.contains("out/shadow/checkpoint.json"), "{message}");
        prop_assert!(!message.contains('\n'), "{message}");
    }
    Ok(())
}

#[test]
fn the_good_checkpoint_loads() {
    let c = Checkpoint::parse(good(), &name()).expect("a fresh checkpoint loads");
    assert!(c.finished);
    assert_eq!(c.history.len(), 3);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(256)
    ))]

    /// Arbitrary bytes.
    #[test]
    fn random_bytes_are_refused(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        prop_assert!(Checkpoint::parse(&bytes, &name()).is_err());
        check(&bytes)?;
    }

    /// A real checkpoint cut short.
    #[test]
    fn truncated_checkpoints_are_refused(cut in 0usize..100_000) {
        let g = good();
        let bytes = &g[..cut % g.len()];
        prop_assert!(Checkpoint::parse(bytes, &name()).is_err());
        check(bytes)?;
    }

    /// A real checkpoint with bytes overwritten.
    #[test]
    fn corrupted_checkpoints_never_panic(
        edits in proptest::collection::vec((0usize..100_000, any::<u8>()), 1..8)
    ) {
        let mut bytes = good().to_vec();
        for (at, b) in edits {
            let n = bytes.len();
            bytes[at % n] = b;
        }
        check(&bytes)?;
    }

    /// A real checkpoint with one number replaced by another (huge, negative, zero, ...):
    /// JSON that parses, with values that may not fit.
    #[test]
    fn checkpoints_with_odd_numbers_never_panic(
        which in 0usize..10_000,
        value in prop_oneof![
            Just("0".to_string()), Just("-1".to_string()), Just("1e308".to_string()),
            Just("18446744073709551615".to_string()), Just("null".to_string()),
            Just("[]".to_string()), Just("\"x\"".to_string()),
            any::<f64>().prop_map(|v| format!("{v:e}")),
            any::<u64>().prop_map(|v| v.to_string()),
        ]
    ) {
        let text = String::from_utf8(good().to_vec()).unwrap();
        // The spans of the numbers in the text.
        let mut spans = Vec::new();
        let mut start = None;
        for (i, c) in text.char_indices() {
            let numeric = c.is_ascii_digit() || "-+.eE".contains(c);
            match (numeric, start) {
                (true, None) => start = Some(i),
                (false, Some(s)) => { spans.push((s, i)); start = None; }
                _ => {}
            }
        }
        let (a, b) = spans[which % spans.len()];
        let edited = format!("{}{}{}", &text[..a], value, &text[b..]);
        check(edited.as_bytes())?;
    }
}
