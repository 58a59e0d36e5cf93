//! The built `pathtracer` binary, run as a user runs it: a bad command line is refused before
//! any work (exit code 2, one line on stderr naming the argument, the value and what is
//! allowed, no files), a run reports its progress, an interrupted run resumes bit for bit,
//! and the pages and exports it writes say what they should.

mod interrupt;
mod pages;
mod refusals;
mod resume;
mod runs;

use std::path::PathBuf;
use std::process::Command;

/// A fresh path in the temporary directory that does not exist yet.
fn fresh(tag: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!("plateau-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&path);
    path
}

/// Runs the binary; returns its exit code and stderr.
fn run(args: &[&str]) -> (Option<i32>, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_pathtracer"))
        .args(args)
        .output()
        .expect("the binary runs");
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// Runs the binary to its end; returns the exit code and stderr.
fn run_in(args: &[String]) -> (Option<i32>, String) {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    run(&args)
}

/// The binary's files in `dir` that must be equal between a run left alone and a run
/// interrupted and resumed: history.csv without its `seconds` column, summary.json without
/// its timings, and the final image (PNG and EXR).
fn results(dir: &std::path::Path) -> (String, String, Vec<u8>, Vec<u8>) {
    let read = |name: &str| std::fs::read(dir.join(name)).unwrap_or_default();
    let history = String::from_utf8_lossy(&read("history.csv"))
        .lines()
        .map(|l| {
            l.rsplit_once(',')
                .map_or(l, |(rest, _seconds)| rest)
                .to_string()
        })
        .collect::<Vec<_>>()
        .join("\n");
    let summary = String::from_utf8_lossy(&read("summary.json"))
        .lines()
        .filter(|l| !l.contains("seconds"))
        .collect::<Vec<_>>()
        .join("\n");
    (history, summary, read("final.png"), read("final.exr"))
}

/// `args` exit 2 with one line naming each of `names`, and nothing is written to `out`.
fn refused_before_any_work(args: &[&str], names: &[&str], out: &std::path::Path) {
    let (code, stderr) = run(args);
    assert_eq!(code, Some(2), "{args:?}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
    for name in names {
        assert!(
            stderr.contains(name),
            "{args:?}: {name:?} not in {stderr:?}"
        );
    }
    assert!(!out.exists(), "{args:?} wrote {out:?}");
}
