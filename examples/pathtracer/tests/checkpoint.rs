//! The bounded fuzz run of the checkpoint loader, on the stable compiler in every `cargo
//! test`, on the path tracer's part of the file (the state after the library's header line,
//! whose own checks the library tests): random bytes, random JSON-like text, and real checkpoints (written by short runs of
//! each kind: the paper's loop interrupted, the adaptive search, a run planned by a time
//! budget, the polished loop on another task) truncated, with bytes flipped, set, inserted,
//! deleted or repeated, with numbers replaced by odd ones (NaN, infinities, huge, negative,
//! out of range) and with their JSON tree edited (values replaced, copied from elsewhere in
//! the file, keys and elements removed or repeated). Every input goes through the one body
//! the cargo-fuzz target runs too, `pathtracer::run::checkpoint::fuzz_checkpoint`: never a
//! panic; a refusal is one line naming the file; a checkpoint that loads matches its task
//! without a panic and loads again once written again.
//!
//! Deterministic: a fixed proptest seed, and real checkpoints whose timings and build are
//! made fixed (the runs themselves are deterministic). `FUZZ_CASES=N` runs N cases per
//! property instead of the default, `FUZZ_SEED=S` another seed: a longer hunt. A failing
//! case is shrunk to a minimal input by proptest and printed; it then becomes a test below
//! (`found_...`).

use std::path::Path;
use std::sync::OnceLock;

use pathtracer::run::checkpoint::fuzz_checkpoint;
use pathtracer::run::{self, Checkpoint, Control, Crn, Method, Settings};
use pathtracer::tasks;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use serde_json::Value;

/// The cases per property when `FUZZ_CASES` is not set: 60,000 inputs, about 1 s in all.
const DEFAULT_CASES: u32 = 10_000;

/// A real checkpoint: the state (after the library's header line) in the file a short run
/// of `task` with `settings` wrote (stopped after `stop_after` iterations if given), and the
/// settings its command line asked for if they differ (a time budget's plan).
fn write_checkpoint(
    tag: &str,
    task: &str,
    settings: &Settings,
    requested: Option<Settings>,
    stop_after: Option<usize>,
) -> Vec<u8> {
    let dir = std::env::temp_dir().join(format!("plateau-ckpt-{tag}-{}", std::process::id()));
    let path = dir.join("checkpoint.json");
    let task = tasks::by_name(task).unwrap();
    let control = Control {
        checkpoint: Some(path.clone()),
        requested,
        stop_after,
        ..Control::default()
    };
    run::optimize_with(&task, settings, control).unwrap();
    let file = plateau_free::lifecycle::Checkpoint::new(&path);
    let (identity, state) = file.read_state().unwrap().unwrap();
    assert!(identity.iter().any(|(name, _)| name == "executable"));
    let _ = std::fs::remove_dir_all(&dir);
    state
}

/// Small settings of `task`: 1 spp, a sixteenth of the resolution, `iterations`.
fn small(task: &str, method: Method, iterations: usize) -> Settings {
    let mut s = Settings::defaults(&tasks::by_name(task).unwrap());
    s.method = method;
    s.iterations = iterations;
    s.eval_every = 2;
    s.spp = 1;
    s.scale = Some(0.0625);
    s
}

/// The real checkpoints, as the runs wrote them (made once).
fn written() -> &'static [Vec<u8>] {
    static BYTES: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let mut adaptive = small("shadow", Method::Adaptive, 6);
        adaptive.crn = Crn::Pair;
        adaptive.seed = 2;
        // What `--budget 100` asks for, and a plan of fewer spp and iterations.
        let mut asked = small("shadow", Method::Plateau, 5);
        asked.spp = 2;
        asked.budget_seconds = Some(100.0);
        let mut planned = asked.clone();
        planned.spp = 1;
        planned.iterations = 3;
        vec![
            // The paper's loop, interrupted after 2 of 4 iterations.
            write_checkpoint(
                "loop",
                "shadow",
                &small("shadow", Method::Plateau, 4),
                None,
                Some(2),
            ),
            write_checkpoint("adaptive", "shadow", &adaptive, None, None),
            write_checkpoint("budget", "shadow", &planned, Some(asked), None),
            write_checkpoint(
                "polished",
                "cup",
                &small("cup", Method::Polished, 4),
                None,
                None,
            ),
            write_checkpoint(
                "image",
                "shadow",
                &small("shadow", Method::Image, 3),
                None,
                Some(2),
            ),
        ]
    })
}

/// The real checkpoints with their timings made fixed: the same bytes every run.
fn seeds() -> &'static [Vec<u8>] {
    static BYTES: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    BYTES.get_or_init(|| {
        written()
            .iter()
            .map(|bytes| {
                let mut c: Checkpoint = serde_json::from_slice(bytes).unwrap();
                c.optimisation_seconds = 1.25;
                c.render_seconds = 0.5;
                for (i, row) in c.history.iter_mut().enumerate() {
                    row.seconds = 0.125 * (i + 1) as f64;
                }
                serde_json::to_vec(&c).unwrap()
            })
            .collect()
    })
}

/// The proptest configuration: `FUZZ_CASES` cases (else [`DEFAULT_CASES`]), a fixed seed
/// (`FUZZ_SEED` to change it), no failure files.
fn config() -> ProptestConfig {
    let env = |name: &str| std::env::var(name).ok().and_then(|v| v.parse().ok());
    ProptestConfig {
        cases: env("FUZZ_CASES").map_or(DEFAULT_CASES, |n: u64| n as u32),
        rng_seed: RngSeed::Fixed(env("FUZZ_SEED").unwrap_or(26)),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

#[test]
fn the_real_checkpoints_load_and_pass_the_fuzz_body() {
    let path = Path::new("out/shadow/checkpoint.json");
    let kinds: Vec<(bool, &str)> = written()
        .iter()
        .map(|bytes| {
            let c = Checkpoint::parse(bytes, path).unwrap_or_else(|e| panic!("{e}"));
            let kind = match c.progress {
                run::Progress::Loop(_) => "loop",
                run::Progress::Adaptive(_) => "adaptive",
                run::Progress::Image(_) => "image",
                _ => "other",
            };
            assert!(!c.history.is_empty());
            (c.finished, kind)
        })
        .collect();
    assert_eq!(
        kinds,
        [
            (false, "loop"),
            (true, "adaptive"),
            (true, "loop"),
            (true, "adaptive"),
            (false, "image")
        ]
    );
    for bytes in seeds() {
        assert!(fuzz_checkpoint(bytes), "a real checkpoint is refused");
    }
}

/// A string of the file that the message quotes (the parser's "unknown variant", another
/// task's name) may hold a line break: the refusal stays one line,
/// the control characters escaped, and at most a few hundred characters.
#[test]
fn found_a_quoted_line_break_stays_on_one_line() {
    let seed = std::str::from_utf8(&seeds()[0]).unwrap();
    let path = Path::new("out/shadow/checkpoint.json");
    let long = "y".repeat(100_000);
    for (from, to) in [
        ("\"sampling\":\"radial\"", "\"sampling\":\"ra\\ndial\""),
        ("\"task\":\"shadow\"", "\"task\":\"sha\\ndow\""),
        (
            "\"sampling\":\"radial\"",
            &format!("\"sampling\":\"{long}\""),
        ),
    ] {
        assert!(seed.contains(from), "{from}");
        let bytes = seed.replacen(from, to, 1);
        // The bad sampler is refused; the other loads (and is refused by the checks after).
        let refused = to.contains("sampling");
        assert_eq!(fuzz_checkpoint(bytes.as_bytes()), !refused, "{from}");
        let task = tasks::by_name("shadow").unwrap();
        let refusal = Checkpoint::parse(bytes.as_bytes(), path).and_then(|c| {
            c.check_matches(&task, &Settings::defaults(&task), path)
                .map(|()| c)
        });
        let message = refusal.expect_err(to).to_string();
        assert!(
            !message.contains('\n') && !message.contains('\r'),
            "{message}"
        );
        assert!(message.chars().count() < 400, "{message}");
    }
}

/// One edit of a checkpoint's bytes; the positions are taken modulo the length.
#[derive(Clone, Debug)]
enum ByteEdit {
    Flip(usize, u8),
    Set(usize, u8),
    Insert(usize, u8),
    Delete(usize),
    /// Repeats the bytes `at..at + len` after them.
    Repeat(usize, usize),
}

fn byte_edit() -> impl Strategy<Value = ByteEdit> {
    let at = 0usize..1 << 20;
    prop_oneof![
        (at.clone(), 0u8..8).prop_map(|(a, bit)| ByteEdit::Flip(a, bit)),
        (at.clone(), any::<u8>()).prop_map(|(a, b)| ByteEdit::Set(a, b)),
        (at.clone(), any::<u8>()).prop_map(|(a, b)| ByteEdit::Insert(a, b)),
        at.clone().prop_map(ByteEdit::Delete),
        (at, 1usize..64).prop_map(|(a, n)| ByteEdit::Repeat(a, n)),
    ]
}

fn apply(bytes: &mut Vec<u8>, edit: &ByteEdit) {
    let n = bytes.len().max(1);
    match *edit {
        ByteEdit::Flip(at, bit) if !bytes.is_empty() => bytes[at % n] ^= 1 << bit,
        ByteEdit::Set(at, b) if !bytes.is_empty() => bytes[at % n] = b,
        ByteEdit::Insert(at, b) => bytes.insert(at % (bytes.len() + 1), b),
        ByteEdit::Delete(at) if !bytes.is_empty() => {
            bytes.remove(at % n);
        }
        ByteEdit::Repeat(at, len) if !bytes.is_empty() => {
            let a = at % n;
            let b = (a + len).min(bytes.len());
            let span = bytes[a..b].to_vec();
            bytes.splice(b..b, span);
        }
        _ => {}
    }
}

/// Odd numbers, as JSON text or not (NaN and the infinities are no JSON, 1e400 is out of
/// range of an f64, 2^64 of a u64).
fn odd_number() -> impl Strategy<Value = String> {
    prop_oneof![
        prop::sample::select(vec![
            "0",
            "-0",
            "-1",
            "0.5",
            "-0.5",
            "1e308",
            "-1e308",
            "1e400",
            "-1e400",
            "1e-400",
            "5e-324",
            "NaN",
            "nan",
            "Infinity",
            "-Infinity",
            "inf",
            "4294967295",
            "4294967296",
            "18446744073709551615",
            "18446744073709551616",
            "-9223372036854775808",
            "-9223372036854775809",
            "1.0000000000000002",
            "1e",
            "--1",
            "0x10",
        ])
        .prop_map(String::from),
        any::<f64>().prop_map(|v| format!("{v:e}")),
        any::<u64>().prop_map(|v| v.to_string()),
        any::<i64>().prop_map(|v| v.to_string()),
    ]
}

/// The byte spans of the numbers in `text`.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = None;
    for (i, c) in text.char_indices() {
        let numeric = c.is_ascii_digit() || "-+.eE".contains(c);
        match (numeric, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                spans.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    spans
}

/// Where a node of a JSON tree is: the keys and indices from the root.
type NodePath = Vec<Step>;

#[derive(Clone, Debug)]
enum Step {
    Key(String),
    Index(usize),
}

/// Every node of `v`, in pre-order (the root first).
fn nodes(v: &Value) -> Vec<NodePath> {
    fn walk(v: &Value, here: &mut NodePath, out: &mut Vec<NodePath>) {
        out.push(here.clone());
        match v {
            Value::Object(map) => {
                for (k, child) in map {
                    here.push(Step::Key(k.clone()));
                    walk(child, here, out);
                    here.pop();
                }
            }
            Value::Array(items) => {
                for (i, child) in items.iter().enumerate() {
                    here.push(Step::Index(i));
                    walk(child, here, out);
                    here.pop();
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(v, &mut Vec::new(), &mut out);
    out
}

fn node_mut<'a>(v: &'a mut Value, path: &[Step]) -> Option<&'a mut Value> {
    path.iter().try_fold(v, |v, step| match step {
        Step::Key(k) => v.get_mut(k),
        Step::Index(i) => v.get_mut(*i),
    })
}

/// One edit of a checkpoint's JSON tree: at the node of index `.0` (modulo their count).
#[derive(Clone, Debug)]
enum TreeEdit {
    /// Replace the node by this value.
    Replace(usize, Value),
    /// Replace the node by a copy of another node (a value of the right kind, misplaced).
    CopyFrom(usize, usize),
    /// Remove the node from its object or array.
    Remove(usize),
    /// Repeat the node in its array (or its first element, if it is an array).
    Repeat(usize),
}

fn odd_value() -> impl Strategy<Value = Value> {
    prop_oneof![
        prop::sample::select(vec![
            Value::Null,
            Value::Bool(true),
            Value::Bool(false),
            Value::from(0),
            Value::from(1),
            Value::from(2),
            Value::from(7),
            Value::from(-1),
            Value::from(u32::MAX),
            Value::from(u64::MAX),
            Value::from(i64::MIN),
            Value::from(1e308),
            Value::from(-1e308),
            Value::from(5e-324),
            Value::from(-0.0),
            Value::from(0.5),
            Value::from(""),
            Value::from("shadow"),
            Value::from("cup"),
            Value::from("texture"),
            Value::from("SHADOW"),
            Value::from("loop"),
            Value::from("adaptive"),
            Value::from("plateau"),
            Value::from("polished"),
            Value::from("fd"),
            Value::from("pair"),
            Value::from("radial"),
            // Strings the messages may echo: a line break, a control character, a long one.
            Value::from("ra\ndial"),
            Value::from("0.2.0\r\u{1b}[2J"),
            Value::from("x".repeat(5000)),
            Value::Array(vec![]),
            Value::Array(vec![Value::from(0.0)]),
            Value::Object(serde_json::Map::new()),
        ]),
        any::<f64>()
            .prop_filter_map("finite", serde_json::Number::from_f64)
            .prop_map(Value::Number),
        any::<u64>().prop_map(Value::from),
        any::<i64>().prop_map(Value::from),
    ]
}

fn tree_edit() -> impl Strategy<Value = TreeEdit> {
    let at = 0usize..1 << 20;
    prop_oneof![
        (at.clone(), odd_value()).prop_map(|(a, v)| TreeEdit::Replace(a, v)),
        (at.clone(), at.clone()).prop_map(|(a, b)| TreeEdit::CopyFrom(a, b)),
        at.clone().prop_map(TreeEdit::Remove),
        at.prop_map(TreeEdit::Repeat),
    ]
}

fn edit_tree(root: &mut Value, edit: &TreeEdit) {
    let all = nodes(root);
    let pick = |i: usize| all[i % all.len()].clone();
    match edit {
        TreeEdit::Replace(at, value) => {
            if let Some(node) = node_mut(root, &pick(*at)) {
                *node = value.clone();
            }
        }
        TreeEdit::CopyFrom(at, from) => {
            let value = node_mut(root, &pick(*from)).map(|v| v.clone());
            if let (Some(node), Some(value)) = (node_mut(root, &pick(*at)), value) {
                *node = value;
            }
        }
        TreeEdit::Remove(at) | TreeEdit::Repeat(at) => {
            let path = pick(*at);
            let Some((last, parent)) = path.split_last() else {
                return;
            };
            let Some(parent) = node_mut(root, parent) else {
                return;
            };
            match (edit, last, parent) {
                (TreeEdit::Remove(_), Step::Key(k), Value::Object(map)) => {
                    map.remove(k);
                }
                (TreeEdit::Remove(_), Step::Index(i), Value::Array(items)) => {
                    items.remove(*i);
                }
                (TreeEdit::Repeat(_), Step::Index(i), Value::Array(items)) => {
                    let item = items[*i].clone();
                    items.insert(*i, item);
                }
                _ => {}
            }
        }
    }
}

proptest! {
    #![proptest_config(config())]

    /// Arbitrary bytes: refused.
    #[test]
    fn random_bytes_are_refused(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        prop_assert!(!fuzz_checkpoint(&bytes));
    }

    /// Random text of JSON's characters.
    #[test]
    fn json_like_text_never_panics(text in r#"[{}\[\]":,0-9eE.+\-a-z ]{0,300}"#) {
        fuzz_checkpoint(text.as_bytes());
    }

    /// A real checkpoint cut short: refused.
    #[test]
    fn truncated_checkpoints_are_refused(which in 0usize..4, cut in 0usize..1 << 20) {
        let g = &seeds()[which];
        prop_assert!(!fuzz_checkpoint(&g[..cut % g.len()]));
    }

    /// A real checkpoint with bytes flipped, set, inserted, deleted or repeated.
    #[test]
    fn checkpoints_with_edited_bytes_never_panic(
        which in 0usize..4,
        edits in proptest::collection::vec(byte_edit(), 1..8),
    ) {
        let mut bytes = seeds()[which].clone();
        for edit in &edits {
            apply(&mut bytes, edit);
        }
        fuzz_checkpoint(&bytes);
    }

    /// A real checkpoint with numbers replaced by odd ones: huge, negative, zero, out of
    /// range, NaN, infinite, malformed.
    #[test]
    fn checkpoints_with_odd_numbers_never_panic(
        which in 0usize..4,
        edits in proptest::collection::vec((0usize..1 << 20, odd_number()), 1..4),
    ) {
        let mut text = String::from_utf8(seeds()[which].clone()).unwrap();
        for (at, number) in &edits {
            let spans = number_spans(&text);
            let (a, b) = spans[at % spans.len()];
            text.replace_range(a..b, number);
        }
        fuzz_checkpoint(text.as_bytes());
    }

    /// A real checkpoint with its JSON tree edited: values replaced by odd ones or by copies
    /// of other parts of the file, keys and elements removed or repeated. The JSON parses, so
    /// these reach the loader's checks of the parts and what `--resume` does next.
    #[test]
    fn checkpoints_with_an_edited_tree_never_panic(
        which in 0usize..4,
        edits in proptest::collection::vec(tree_edit(), 1..5),
    ) {
        let mut root: Value = serde_json::from_slice(&seeds()[which]).unwrap();
        for edit in &edits {
            edit_tree(&mut root, edit);
        }
        fuzz_checkpoint(&serde_json::to_vec(&root).unwrap());
    }
}
