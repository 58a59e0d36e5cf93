//! The built `pathtracer` binary refuses a bad command line before any work: exit code 2,
//! one line on stderr naming the argument, the value and what is allowed, and no files.

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

#[test]
fn bad_values_exit_2_on_one_line_and_write_nothing() {
    for (option, value, allowed) in [
        ("--sigma0", "-1", "> 0"),
        ("--eval-every", "0", ">= 1"),
        ("--iterations", "0", ">= 1"),
        ("--lr", "NaN", "finite"),
        ("--samples", "3", "even"),
    ] {
        let out = fresh(option.trim_start_matches('-'));
        let out_arg = out.display().to_string();
        let (code, stderr) = run(&["optimize", "shadow", option, value, "--out", &out_arg]);
        assert_eq!(code, Some(2), "{option} {value}: {stderr}");
        assert_eq!(
            stderr.trim_end().lines().count(),
            1,
            "{option} {value}: {stderr}"
        );
        for part in [option, value, allowed] {
            assert!(
                stderr.contains(part),
                "{option} {value}: {part:?} not in {stderr:?}"
            );
        }
        assert!(
            !out.exists(),
            "{option} {value}: {} was created",
            out.display()
        );
    }
}

#[test]
fn help_exits_0() {
    let output = Command::new(env!("CARGO_BIN_EXE_pathtracer"))
        .args(["optimize", "--help"])
        .output()
        .expect("the binary runs");
    assert_eq!(output.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&output.stdout).contains("[default: the task's]"));
}
