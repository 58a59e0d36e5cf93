//! Command lines refused before any work: bad values, combinations that cannot run, counts
//! and scales too large to run, outputs that cannot be written; and the messages that are
//! not errors (`--help`, `--version`).

use std::process::Command;

use crate::{fresh, run};

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

/// `all --stop-when-stalled` takes a fraction of the budget in (0, 1]; anything else exits 2
/// naming the option and the value, before any run.
#[test]
fn all_refuses_a_bad_stall_fraction() {
    for value in ["0", "-0.1", "1.5", "NaN", "often"] {
        let out = fresh("all-stall");
        let out_arg = out.display().to_string();
        let (code, stderr) = run(&[
            "all",
            "--tasks",
            "shadow",
            "--stop-when-stalled",
            value,
            "--out",
            &out_arg,
        ]);
        assert_eq!(code, Some(2), "{value}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{value}: {stderr}");
        for part in ["--stop-when-stalled", value, "fraction of the budget"] {
            assert!(stderr.contains(part), "{value}: {part:?} not in {stderr:?}");
        }
        assert!(!out.exists(), "{value}: {} was created", out.display());
    }
}

/// `--polish` is refused outside [0, 1) and with any method but polished, by `optimize` and
/// `all`: exit 2, one line naming it, nothing written.
#[test]
fn a_bad_polish_share_is_refused_before_any_work() {
    let cases: [(&[&str], &str, &str); 6] = [
        (
            &["optimize", "shadow", "--polish", "1"],
            "1",
            ">= 0 and < 1",
        ),
        (
            &["optimize", "shadow", "--polish", "-0.1"],
            "-0.1",
            ">= 0 and < 1",
        ),
        (
            &["all", "--tasks", "shadow", "--polish", "NaN"],
            "NaN",
            ">= 0 and < 1",
        ),
        (
            &[
                "optimize", "shadow", "--method", "plateau", "--polish", "0.5",
            ],
            "0.5",
            "--method polished",
        ),
        (
            &["optimize", "shadow", "--budget", "5", "--polish", "0.5"],
            "0.5",
            "--method polished",
        ),
        (
            &[
                "all", "--tasks", "shadow", "--method", "adaptive", "--polish", "0.5",
            ],
            "0.5",
            "--method polished",
        ),
    ];
    for (args, value, allowed) in cases {
        let out = fresh("polish");
        let out_arg = out.display().to_string();
        let mut line = args.to_vec();
        line.extend(["--out", &out_arg]);
        let (code, stderr) = run(&line);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        for part in ["--polish", value, allowed] {
            assert!(
                stderr.contains(part),
                "{args:?}: {part:?} not in {stderr:?}"
            );
        }
        assert!(!out.exists(), "{args:?}: {} was created", out.display());
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

/// Extreme counts and scales: an iteration count near `usize::MAX` (the paper's loop must not
/// reserve a history row for each, the adaptive search's budget N x iterations must not wrap
/// to 0), a scale of 1e300 and a huge N (whose allocations would overflow: refused while
/// parsing). Each runs (stopped after an iteration) or is refused, never a panic.
#[test]
fn found_extreme_counts_and_scales_run_or_are_refused_without_a_panic() {
    let out = fresh("extreme");
    let o = out.display().to_string();
    let max = usize::MAX.to_string();
    for (extra, expected) in [
        (vec!["--iterations", &max, "--method", "plateau"], 130),
        (vec!["--iterations", &max, "--method", "fd"], 130),
        (
            // 2^48 x 2^16 evaluations: 0 once wrapped.
            vec![
                "--iterations",
                "281474976710656",
                "--method",
                "adaptive",
                "--samples",
                "65536",
            ],
            130,
        ),
        (vec!["--iterations", &max, "--method", "polished"], 130),
        (
            vec![
                "--eval-every",
                &max,
                "--iterations",
                "3",
                "--method",
                "plateau",
            ],
            130,
        ),
        (vec!["--scale", "1e300"], 2),
        (
            vec![
                "--scale",
                "1e-300",
                "--iterations",
                "3",
                "--method",
                "plateau",
            ],
            130,
        ),
        (vec!["--samples", "18446744073709551614"], 2),
    ] {
        let mut args = vec![
            "optimize",
            "shadow",
            "--scale",
            "0.0625",
            "--spp",
            "1",
            "--stop-after",
            "1",
            "--quiet",
            "--out",
            &o,
        ];
        args.extend(&extra);
        // The last --scale counts: clap refuses a repeated one, so drop the default's.
        if extra.contains(&"--scale") {
            args.drain(2..4);
        }
        let (code, err) = run(&args);
        assert!(!err.contains("panicked"), "{extra:?}: {err}");
        assert_eq!(code, Some(expected), "{extra:?}: {err}");
        let _ = std::fs::remove_dir_all(&out);
    }
}

/// Combinations that cannot run are refused before any work, like a bad value: exit 2, one
/// line naming the arguments, no files.
#[test]
fn impossible_combinations_exit_2_before_any_work() {
    let out = fresh("combination");
    let o = out.display().to_string();
    for (args, named) in [
        (
            vec![
                "optimize", "shadow", "--method", "adaptive", "--budget", "5", "--out", &o,
            ],
            "--budget",
        ),
        (
            vec![
                "optimize", "shadow", "--method", "polished", "--budget", "5", "--out", &o,
            ],
            "--budget",
        ),
        (
            vec!["optimize", "shadow", "--out", &o, "--resume", &o],
            "--resume",
        ),
        (vec!["seeds", "--runs", &o], "--runs"),
    ] {
        let t = std::time::Instant::now();
        let (code, stderr) = run(&args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(named), "{stderr}");
        assert!(t.elapsed().as_secs_f64() < 1.0);
        assert!(!out.exists());
    }
}

/// An output that cannot be written (`--out` of every command that writes, `render --out`,
/// `--page`, and `optimize`'s default `out/<task>` in a directory that cannot be written) is
/// refused before any work: exit 2 within seconds, one line naming the option, the value and
/// why.
#[test]
fn outputs_that_cannot_be_written_are_refused_before_any_work() {
    for args in [
        &["optimize", "shadow", "--out", "/proc/nope"][..],
        &["all", "--out", "/proc/nope/deeper"],
        &["experiment", "fig1", "--out", "/proc/nope"],
        &["export", "cup", "--out", "/proc/nope"],
        &["render", "cup", "--out", "/proc/nope.png"],
        &["seeds", "--runs", ".", "--page", "/proc/nope.md"],
    ] {
        let started = std::time::Instant::now();
        let (code, stderr) = run(args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        let option = args[args.len() - 2];
        let value = args[args.len() - 1];
        for part in [
            format!("'{value}'"),
            format!("'{option} <"),
            "cannot write there".into(),
        ] {
            assert!(
                stderr.contains(&part),
                "{args:?}: {part:?} not in {stderr:?}"
            );
        }
        assert!(
            started.elapsed().as_secs() < 10,
            "{args:?}: not before the work"
        );
    }
    let output = Command::new(env!("CARGO_BIN_EXE_pathtracer"))
        .args(["optimize", "shadow", "--iterations", "1"])
        .current_dir("/proc")
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("'out/shadow' for '--out <OUT>' (its default): cannot write there"),
        "{stderr}"
    );
}

/// A misspelt option or subcommand is refused on one line that keeps clap's "did you mean".
#[test]
fn a_misspelling_is_refused_on_one_line_with_the_tip() {
    for (args, tip) in [
        (
            &["optimize", "shadow", "--iteration", "3"][..],
            "; tip: a similar argument exists: '--iterations'",
        ),
        (&["optimise", "shadow"], "'optimize'"),
        (&["all", "--seed", "2"], "'--seeds'"),
    ] {
        let (code, stderr) = run(args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert!(stderr.contains("tip: "), "{args:?}: no tip in {stderr:?}");
        assert!(stderr.contains(tip), "{args:?}: {tip:?} not in {stderr:?}");
    }
}

/// `--version` prints the package's name and version and exits 0.
#[test]
fn version_prints_the_version() {
    let output = Command::new(env!("CARGO_BIN_EXE_pathtracer"))
        .arg("--version")
        .output()
        .expect("the binary runs");
    assert_eq!(output.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&output.stdout).trim(),
        format!("pathtracer {}", env!("CARGO_PKG_VERSION"))
    );
}
