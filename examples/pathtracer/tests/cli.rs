//! The built `pathtracer` binary refuses a bad command line before any work: exit code 2,
//! one line on stderr naming the argument, the value and what is allowed, and no files.

use std::path::{Path, PathBuf};
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

/// The renders after which a polished run's loop handed over: its final evaluation's row,
/// the one at sigma 0.
fn hand_over(dir: &Path) -> usize {
    let history = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let header: Vec<&str> = history.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (sigma, renders) = (column("sigma"), column("renders"));
    history
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .find(|row| row[sigma].parse::<f64>().unwrap() == 0.0)
        .map(|row| row[renders].parse().unwrap())
        .expect("a row at sigma 0")
}

/// The default share, 0.5, hands over after half the renders (40 of 80: the start, 19
/// iterations of 2 and the final evaluation) where `--polish 0.25` hands over after 60; the
/// summary says the share.
#[test]
fn the_polish_share_sets_where_the_loop_hands_over() {
    let mut at = Vec::new();
    for share in [None, Some("0.25")] {
        let out = fresh(&format!("polish-at-{}", share.unwrap_or("default")));
        let out_arg = out.display().to_string();
        let mut line = vec![
            "optimize",
            "shadow",
            "--scale",
            "0.125",
            "--spp",
            "2",
            "--iterations",
            "40",
            "--method",
            "polished",
            "--quiet",
            "--out",
            &out_arg,
        ];
        line.extend(share.iter().flat_map(|s| ["--polish", *s]));
        let (code, stderr) = run(&line);
        assert_eq!(code, Some(0), "{stderr}");
        at.push(hand_over(&out));
        let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
        let polish = format!("\"polish\": {}", share.unwrap_or("0.5"));
        assert!(summary.contains(&polish), "{polish} not in {summary}");
        let _ = std::fs::remove_dir_all(&out);
    }
    assert_eq!(at, [40, 60]);
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

/// Runs the binary to its end; returns the exit code and stderr.
fn run_in(args: &[String]) -> (Option<i32>, String) {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    run(&args)
}

/// A run stopped after k iterations (the Ctrl-C path, through the hidden `--stop-after`)
/// exits 130 with its outputs written and marked interrupted, prints the command that
/// resumes; continued with `--resume`, it ends bit-identical to the run left alone: for the
/// paper's loop with each renderer-seed rule, finite differences, the adaptive search and the
/// polished loop (stopped inside the loop; the polish runs after the resume).
#[test]
fn an_interrupted_run_resumed_equals_the_run_left_alone() {
    for (tag, extra) in [
        ("fixed", &["--iterations", "12", "--method", "plateau"][..]),
        (
            "pair",
            &["--iterations", "12", "--crn", "pair", "--method", "plateau"][..],
        ),
        ("fd", &["--iterations", "6", "--method", "fd"][..]),
        (
            "adaptive",
            &[
                "--iterations",
                "60",
                "--method",
                "adaptive",
                "--crn",
                "pair",
            ][..],
        ),
        (
            "polished",
            &["--iterations", "40", "--method", "polished"][..],
        ),
        (
            "polished-half",
            &[
                "--iterations",
                "40",
                "--method",
                "polished",
                "--polish",
                "0.5",
            ][..],
        ),
    ] {
        let base: Vec<String> = ["optimize", "shadow", "--scale", "0.125", "--spp", "2"]
            .iter()
            .chain(extra)
            .chain(&["--eval-every", "2", "--quiet"])
            .map(|s| s.to_string())
            .collect();
        let alone = fresh(&format!("alone-{tag}"));
        let cut = fresh(&format!("cut-{tag}"));
        let with = |more: &[&str]| {
            let mut v = base.clone();
            v.extend(more.iter().map(|s| s.to_string()));
            v
        };
        let (code, err) = run_in(&with(&["--out", &alone.display().to_string()]));
        assert_eq!(code, Some(0), "{tag}: {err}");
        let (code, err) = run_in(&with(&[
            "--out",
            &cut.display().to_string(),
            "--stop-after",
            "3",
            "--checkpoint-every",
            "2",
        ]));
        assert_eq!(code, Some(130), "{tag}: {err}");
        assert!(
            err.contains(&format!("--resume {}", cut.display())),
            "{tag}: no resume command in {err}"
        );
        let summary = std::fs::read_to_string(cut.join("summary.json")).unwrap();
        assert!(summary.contains("\"interrupted\": true"), "{tag}");
        for file in ["history.csv", "final.png", "final.exr", "checkpoint.json"] {
            assert!(cut.join(file).is_file(), "{tag}: no {file}");
        }
        assert_eq!(
            std::fs::read_to_string(cut.join("history.csv"))
                .unwrap()
                .lines()
                .count(),
            4,
            "{tag}: three iterations and the header"
        );
        let (code, err) = run_in(&with(&["--resume", &cut.display().to_string()]));
        assert_eq!(code, Some(0), "{tag}: {err}");
        let (a, b) = (results(&alone), results(&cut));
        assert_eq!(a.0, b.0, "{tag}: history.csv differs");
        assert_eq!(a.1, b.1, "{tag}: summary.json differs");
        assert!(a.2 == b.2 && a.3 == b.3, "{tag}: the final image differs");
        assert!(b.1.contains("\"interrupted\": false"), "{tag}");
        // The render counts are among what the resumed run gets right.
        assert!(
            b.0.starts_with("iteration,sigma,loss,param_mse,image_mse,renders,eval_renders")
                && b.1.contains("\"renders\": "),
            "{tag}"
        );
        let _ = std::fs::remove_dir_all(&alone);
        let _ = std::fs::remove_dir_all(&cut);
    }
}

/// `--resume DIR` alone continues the run in DIR with the settings of its checkpoint, none
/// of them the defaults (seed 2, renderer seeds per pair, a learning rate, a resolution, an
/// spp, iterations and a curve cadence of their own), and ends bit for bit as the run left
/// alone; the command an interrupted run prints is that (`optimize shadow --resume DIR`, and
/// the options that are not settings). Before that, an option that contradicts the
/// checkpoint, or another task, exits 2 within a second on one line naming the option and
/// both values, and changes nothing; options that agree are accepted, and the task may be
/// left out (the adaptive search's case).
#[test]
fn resume_from_the_folder_alone_equals_the_run_left_alone() {
    for (tag, settings, resume_with) in [
        (
            "plateau",
            &[
                "--method",
                "plateau",
                "--seed",
                "2",
                "--crn",
                "pair",
                "--lr",
                "0.02",
                "--iterations",
                "12",
                "--eval-every",
                "3",
            ][..],
            None,
        ),
        (
            "adaptive",
            &[
                "--method",
                "adaptive",
                "--seed",
                "2",
                "--sigma0",
                "0.4",
                "--iterations",
                "60",
            ][..],
            Some(&["optimize", "--seed", "2", "--method", "adaptive", "--quiet"][..]),
        ),
    ] {
        let base: Vec<String> = ["optimize", "shadow", "--scale", "0.125", "--spp", "3"]
            .iter()
            .chain(settings)
            .chain(&["--quiet"])
            .map(|s| s.to_string())
            .collect();
        let alone = fresh(&format!("folder-alone-{tag}"));
        let cut = fresh(&format!("folder-cut-{tag}"));
        let (a, c) = (alone.display().to_string(), cut.display().to_string());
        let with = |more: &[&str]| {
            let mut v = base.clone();
            v.extend(more.iter().map(|s| s.to_string()));
            v
        };
        let (code, err) = run_in(&with(&["--out", &a]));
        assert_eq!(code, Some(0), "{tag}: {err}");
        let (code, err) = run_in(&with(&["--out", &c, "--stop-after", "3"]));
        assert_eq!(code, Some(130), "{tag}: {err}");
        let printed = err
            .lines()
            .find_map(|l| l.strip_prefix("interrupted; to continue: "))
            .unwrap_or_else(|| panic!("{tag}: no resume command in {err}"));
        let bin = env!("CARGO_BIN_EXE_pathtracer");
        assert_eq!(
            printed,
            format!("{bin} optimize shadow --resume {c} --quiet"),
            "{tag}"
        );

        let checkpoint = std::fs::read(cut.join("checkpoint.json")).unwrap();
        for (more, named) in [
            (
                &["optimize", "shadow", "--seed", "3"][..],
                ["--seed 3", "seed is 2 in", "3 here"],
            ),
            (
                &["optimize", "--spp", "8"][..],
                ["--spp 8", "spp is 3 in", "8 here"],
            ),
            (
                &["optimize", "--no-anneal"][..],
                ["--no-anneal", "anneal is true in", "false here"],
            ),
            (
                &["optimize", "--method", "fd"][..],
                ["--method fd", "method is ", "fd here"],
            ),
            (
                &["optimize", "cup"][..],
                ["--resume", "task is shadow in", "cup here"],
            ),
        ] {
            let mut args = more.to_vec();
            args.extend(["--resume", &c, "--quiet"]);
            let t = std::time::Instant::now();
            let (code, err) = run(&args);
            assert_eq!(code, Some(2), "{tag} {more:?}: {err}");
            assert_eq!(err.trim_end().lines().count(), 1, "{tag} {more:?}: {err}");
            for part in named {
                assert!(err.contains(part), "{tag} {more:?}: {part:?} not in {err}");
            }
            assert!(t.elapsed().as_secs_f64() < 1.0, "{tag} {more:?}: slow");
            assert_eq!(
                std::fs::read(cut.join("checkpoint.json")).unwrap(),
                checkpoint,
                "{tag} {more:?}: the checkpoint changed"
            );
        }

        let resume: Vec<String> = match resume_with {
            // The printed command, word for word (the paths have no spaces).
            None => printed.split(' ').skip(1).map(String::from).collect(),
            Some(args) => args
                .iter()
                .map(|s| s.to_string())
                .chain(["--resume".into(), c.clone()])
                .collect(),
        };
        let (code, err) = run_in(&resume);
        assert_eq!(code, Some(0), "{tag}: {resume:?}: {err}");
        assert!(err.contains("resuming"), "{tag}: {err}");
        let (left_alone, resumed) = (results(&alone), results(&cut));
        assert_eq!(left_alone.0, resumed.0, "{tag}: history.csv differs");
        assert_eq!(left_alone.1, resumed.1, "{tag}: summary.json differs");
        assert!(
            left_alone.2 == resumed.2 && left_alone.3 == resumed.3,
            "{tag}: the final image differs"
        );
        for part in ["\"interrupted\": false", "\"seed\": 2"] {
            assert!(
                resumed.1.contains(part),
                "{tag}: no {part} in {}",
                resumed.1
            );
        }
        let _ = std::fs::remove_dir_all(&alone);
        let _ = std::fs::remove_dir_all(&cut);
    }
}

/// Found by fuzzing the numeric options (regressions): an iteration count near `usize::MAX`
/// made the paper's loop reserve a history row for each (a capacity-overflow panic) and the
/// adaptive search's budget N x iterations wrap to 0 (a wrong error); a scale of 1e300
/// overflowed the image's allocation and a huge N the estimator's (both now refused while
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

/// `--resume` of a missing, damaged, foreign or mismatched checkpoint exits 2 within a
/// second, on one line naming `--resume`, the file and what is wrong, and writes nothing.
#[test]
fn bad_checkpoints_are_refused_before_any_work() {
    let dir = fresh("refuse");
    let d = dir.display().to_string();
    let small = [
        "--scale",
        "0.125",
        "--spp",
        "2",
        "--iterations",
        "4",
        "--quiet",
    ];
    // The paper's loop (not the default polished one): its checkpoint has the fields below.
    let mut args = vec!["optimize", "shadow", "--out", &d, "--checkpoint-every", "0"];
    args.extend(small);
    args.extend(["--method", "plateau"]);
    assert_eq!(run(&args).0, Some(0));
    let good = std::fs::read_to_string(dir.join("checkpoint.json")).unwrap();
    let listing = |d: &std::path::Path| {
        let mut names: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        names
    };
    let before = listing(&dir);
    let missing = fresh("refuse-missing").display().to_string();
    let cases: Vec<(String, Vec<&str>, &str)> = vec![
        (good.clone(), vec!["--resume", &missing], "checkpoint.json"),
        (good[..good.len() / 2].into(), vec![], "is damaged"),
        ("not json".into(), vec![], "is damaged"),
        (
            good.replacen("\"format\":1", "\"format\":7", 1),
            vec![],
            "format 7",
        ),
        (
            good.replacen("\"executable\":\"", "\"executable\":\"0", 1),
            vec![],
            "another build",
        ),
        (good.clone(), vec!["--crn", "pair"], "crn is fixed in"),
        (good.clone(), vec!["--no-anneal"], "anneal is true in"),
        (good.clone(), vec!["--seed", "3"], "seed is 0 in"),
        (good.clone(), vec!["--method", "fd"], "method is plateau in"),
        (
            good.replacen("\"iteration\":4", "\"iteration\":3", 1),
            vec![],
            "inconsistent",
        ),
    ];
    for (contents, more, expected) in cases {
        std::fs::write(dir.join("checkpoint.json"), &contents).unwrap();
        let mut args = vec!["optimize", "shadow"];
        args.extend(small);
        args.extend(&more);
        if !more.contains(&"--method") {
            args.extend(["--method", "plateau"]);
        }
        if !more.contains(&"--resume") {
            args.extend(["--resume", &d]);
        }
        let t = std::time::Instant::now();
        let (code, err) = run(&args);
        let seconds = t.elapsed().as_secs_f64();
        assert_eq!(code, Some(2), "{expected}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{expected}: {err}");
        assert!(
            err.contains("--resume") && err.contains(expected),
            "{expected}: {err}"
        );
        assert!(seconds < 1.0, "{expected}: {seconds} s");
        assert_eq!(listing(&dir), before, "{expected}: files changed");
        assert!(!std::path::Path::new(&missing).exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Sends SIGINT to a child process (the `kill` command: no dependency for a test).
fn interrupt(child: &std::process::Child) {
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
}

/// Waits (up to a minute) until `path` exists.
fn wait_for(path: &std::path::Path) {
    let t = std::time::Instant::now();
    while !path.exists() {
        assert!(
            t.elapsed().as_secs() < 60,
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// A real Ctrl-C (SIGINT) after the first iteration: the run finishes its iteration,
/// writes the checkpoint and every output (summary marked interrupted), prints the command
/// that resumes and exits 130; `--resume` then ends as the run left alone.
#[test]
fn ctrl_c_writes_everything_exits_130_and_resumes_bit_identical() {
    let alone = fresh("sigint-alone");
    let cut = fresh("sigint-cut");
    let base = [
        "optimize",
        "shadow",
        "--scale",
        "0.25",
        "--spp",
        "8",
        "--iterations",
        "300",
        "--eval-every",
        "10",
        "--quiet",
        "--method",
        "plateau",
    ];
    let mut child = Command::new(env!("CARGO_BIN_EXE_pathtracer"))
        .args(base)
        .args([
            "--out",
            &cut.display().to_string(),
            "--checkpoint-every",
            "1",
        ])
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("the binary runs");
    // The first checkpoint is written after the first iteration.
    wait_for(&cut.join("checkpoint.json"));
    interrupt(&child);
    let status = child.wait().expect("the run ends");
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("--resume"), "{stderr}");
    let summary = std::fs::read_to_string(cut.join("summary.json")).unwrap();
    assert!(summary.contains("\"interrupted\": true"), "{summary}");
    let rows = std::fs::read_to_string(cut.join("history.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert!((1..300).contains(&rows), "{rows} iterations done");
    for file in ["final.png", "final.exr", "progress.png", "convergence.png"] {
        assert!(cut.join(file).is_file(), "no {file}");
    }

    let mut resume: Vec<&str> = base.to_vec();
    let cut_arg = cut.display().to_string();
    resume.extend(["--resume", &cut_arg]);
    let (code, err) = run(&resume);
    assert_eq!(code, Some(0), "{err}");
    let mut whole: Vec<&str> = base.to_vec();
    let alone_arg = alone.display().to_string();
    whole.extend(["--out", &alone_arg]);
    assert_eq!(run(&whole).0, Some(0));
    let (a, b) = (results(&alone), results(&cut));
    assert_eq!(a.0, b.0, "history.csv differs");
    assert_eq!(a.1, b.1, "summary.json differs");
    assert!(a.2 == b.2 && a.3 == b.3, "the final image differs");
    let _ = std::fs::remove_dir_all(&alone);
    let _ = std::fs::remove_dir_all(&cut);
}

/// A second Ctrl-C exits at once (130), without waiting for the iteration or writing the
/// outputs; the last checkpoint stays whole and resumable.
#[test]
fn a_second_ctrl_c_exits_at_once() {
    let dir = fresh("sigint-twice");
    // Slow iterations (two full-resolution renders at 64 spp, about a second each).
    let mut child = Command::new(env!("CARGO_BIN_EXE_pathtracer"))
        .args([
            "optimize",
            "shadow",
            "--spp",
            "64",
            "--iterations",
            "50",
            "--method",
            "plateau",
            "--quiet",
            "--checkpoint-every",
            "1",
            "--out",
        ])
        .arg(&dir)
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("the binary runs");
    wait_for(&dir.join("checkpoint.json"));
    interrupt(&child);
    std::thread::sleep(std::time::Duration::from_millis(50));
    interrupt(&child);
    let status = child.wait().expect("the run ends");
    assert_eq!(status.code(), Some(130));
    assert!(!dir.join("summary.json").exists(), "outputs were written");
    let checkpoint = std::fs::read_to_string(dir.join("checkpoint.json")).unwrap();
    assert!(checkpoint.ends_with('}'), "the checkpoint is whole");
    let _ = std::fs::remove_dir_all(&dir);
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

#[test]
fn the_seeds_page_puts_studies_side_by_side() {
    // The paper loop's committed seeds study (docs/results/seeds-paper), its SHADOW and CUP
    // runs copied alone (summaries only): seeds 0-9 each, 8 and 2 of them at or below the
    // paper's parameter MSE, 7 and 7 at or below its image MSE.
    let committed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/results/seeds-paper");
    let runs = fresh("seeds-runs");
    for task in ["shadow", "cup"] {
        for k in 0..10 {
            let name = match k {
                0 => task.to_string(),
                k => format!("{task}-seed{k}"),
            };
            std::fs::create_dir_all(runs.join(&name)).unwrap();
            for file in ["summary.json", "history.csv"] {
                std::fs::copy(
                    committed.join(&name).join(file),
                    runs.join(&name).join(file),
                )
                .expect("the committed study has this run");
            }
        }
    }
    let page = fresh("seeds").join("seeds.md");
    let page_arg = page.display().to_string();
    let runs_arg = runs.display().to_string();
    let (code, stderr) = run(&["seeds", "--runs", &runs_arg, "--page", &page_arg]);
    assert_eq!(code, Some(0), "{stderr}");
    let md = std::fs::read_to_string(&page).expect("the page is written");
    assert!(
        md.contains("## SHADOW (paper's parameter MSE 1.81e-3)"),
        "{md}"
    );
    assert!(md.contains("## CUP"), "{md}");
    assert!(md.contains("| at or below the paper | 8 of 10 |"), "{md}");
    assert!(md.contains("| at or below the paper | 2 of 10 |"), "{md}");
    assert!(
        md.contains("| image MSE at or below the paper's (1.74e-5) | 7 of 10 |")
            && md.contains("| image MSE at or below the paper's (4.92e-6) | 7 of 10 |"),
        "{md}"
    );
    // Seed 1 of SHADOW left the frame (5.63), seed 0 did not (2.21e-7, bold).
    assert!(
        md.contains("| 1 | 5.63e0 |") && md.contains("| 0 | **2.21e-7** |"),
        "{md}"
    );
    // The renders to the paper's parameter MSE, derived from the histories (written before
    // the runs counted: N renders per iteration of the paper's loop, N = 2 for both): SHADOW
    // reached 1.81e-3 in 8 of 10 runs, CUP 4.18e-7 in 9 of 10 (then left it again in 7).
    assert!(
        md.contains("| reached the paper's parameter MSE (renders counted) | 8 of 10 |")
            && md.contains(
                "| renders to the paper's parameter MSE: median [min, max] | 469 [246, never] |"
            ),
        "{md}"
    );
    assert!(
        md.contains("| reached the paper's parameter MSE (renders counted) | 9 of 10 |")
            && md.contains(
                "| renders to the paper's parameter MSE: median [min, max] | 753 [724, never] |"
            ),
        "{md}"
    );
    assert!(
        md.contains("| renders of the objective per run (median) | 800 |"),
        "{md}"
    );
    assert!(!md.contains("## GI"), "tasks without runs have no section");
    let _ = std::fs::remove_dir_all(&runs);
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

#[test]
fn export_writes_the_scene_and_refuses_bad_input_before_any_work() {
    let out = fresh("export");
    let out_arg = out.display().to_string();
    for (args, names) in [
        (
            vec!["export", "nope", "--out", &out_arg],
            vec!["nope", "shadow"],
        ),
        (
            vec!["export", "shadow", "--params", "1", "--out", &out_arg],
            vec!["--params", "2"],
        ),
        (
            vec!["export", "shadow", "--spp", "0", "--out", &out_arg],
            vec!["--spp", ">= 1"],
        ),
        (
            vec!["export", "shadow", "--scale", "-1", "--out", &out_arg],
            vec!["--scale", "> 0"],
        ),
    ] {
        refused_before_any_work(&args, &names, &out);
    }
    let (code, stderr) = run(&[
        "export",
        "cup",
        "--initial",
        "--spp",
        "8",
        "--out",
        &out_arg,
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let text = std::fs::read_to_string(out.join("scene.json")).expect("scene.json");
    let scene: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(scene["format"], "pathtracer-scene 1");
    assert_eq!(
        (scene["task"].as_str(), scene["params"].as_str()),
        (Some("cup"), Some("start"))
    );
    assert_eq!(scene["spp"], 8);
    assert_eq!(scene["theta"][0], 0.5);
    let obj = std::fs::read_to_string(out.join("mesh-0.obj")).expect("the mug's mesh");
    assert_eq!(obj.lines().filter(|l| l.starts_with("f ")).count(), 1280);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn export_reads_params_from_a_file_and_refuses_a_bad_one_before_any_work() {
    let dir = fresh("params-file");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("out");
    let out_arg = out.display().to_string();
    let file = |name: &str, text: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path.display().to_string()
    };
    let missing = dir.join("missing.json").display().to_string();
    let short = file("short.json", "[0.5]");
    let words = file("words.json", "0.5, 0.5");
    let huge = file("huge.json", "[0.5, 1e999]");
    let good = file("good.json", "[0.25, 0.75]\n");
    for (args, names) in [
        (
            vec!["--params-file", missing.as_str()],
            vec!["--params-file", "missing.json", "read"],
        ),
        (
            vec!["--params-file", short.as_str()],
            vec!["--params-file", "short.json", "1 values", "2"],
        ),
        (
            vec!["--params-file", words.as_str()],
            vec!["--params-file", "words.json", "JSON array"],
        ),
        (
            vec!["--params-file", huge.as_str()],
            vec!["--params-file", "huge.json"],
        ),
        (
            vec!["--params-file", good.as_str(), "--initial"],
            vec!["--params-file", "--initial"],
        ),
        (
            vec!["--params-file", good.as_str(), "--params", "1,2"],
            vec!["--params-file", "--params"],
        ),
    ] {
        let mut all = vec!["export", "shadow", "--out", &out_arg];
        all.extend(&args);
        refused_before_any_work(&all, &names, &out);
    }
    let (code, stderr) = run(&[
        "export",
        "shadow",
        "--params-file",
        &good,
        "--out",
        &out_arg,
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let text = std::fs::read_to_string(out.join("scene.json")).expect("scene.json");
    let scene: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(scene["params"], "given");
    assert_eq!(scene["theta"], serde_json::json!([0.25, 0.75]));
    // TEXTURE's 49,152 parameters go to theta.json, which --params-file reads back: the
    // start exported again from its own theta.json is the same start.
    let start = dir.join("start");
    let (code, stderr) = run(&[
        "export",
        "texture",
        "--initial",
        "--scale",
        "0.125",
        "--out",
        &start.display().to_string(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(start.join("scene.json")).unwrap()).unwrap();
    assert!(scene.get("theta").is_none());
    assert_eq!(scene["theta_file"], "theta.json");
    let theta: Vec<f64> =
        serde_json::from_str(&std::fs::read_to_string(start.join("theta.json")).unwrap()).unwrap();
    assert_eq!(theta.len(), 49_152);
    assert!(theta.iter().all(|&t| t == 0.5));
    let again = dir.join("again");
    let theta_file = start.join("theta.json").display().to_string();
    let (code, stderr) = run(&[
        "export",
        "texture",
        "--params-file",
        &theta_file,
        "--scale",
        "0.125",
        "--out",
        &again.display().to_string(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    // The same parameters back (the EXR's bytes may differ: its blocks are compressed in
    // parallel and written in the order they finish).
    assert_eq!(
        std::fs::read_to_string(start.join("theta.json")).unwrap(),
        std::fs::read_to_string(again.join("theta.json")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
