//! Stopped runs continued with `--resume` end bit for bit as the runs left alone; bad
//! checkpoints are refused before any work.

use crate::{fresh, results, run, run_in};

/// A run stopped after k iterations (the Ctrl-C path, through the hidden `--stop-after`)
/// exits 130 with its outputs written and marked interrupted, prints the command that
/// resumes; continued with `--resume`, it ends bit-identical to the run left alone: for the
/// paper's loop with each renderer-seed rule, finite differences, SPSA, the adaptive search
/// the polished loop (stopped inside the loop; the polish runs after the resume) and the
/// image method.
#[test]
fn an_interrupted_run_resumed_equals_the_run_left_alone() {
    for (tag, extra) in [
        ("fixed", &["--iterations", "12", "--method", "plateau"][..]),
        (
            "pair",
            &["--iterations", "12", "--crn", "pair", "--method", "plateau"][..],
        ),
        ("fd", &["--iterations", "6", "--method", "fd"][..]),
        ("spsa", &["--iterations", "6", "--method", "spsa"][..]),
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
        ("image", &["--iterations", "4", "--method", "image"][..]),
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
            good.replacen("\"format\":2", "\"format\":7", 1),
            vec![],
            "format 7",
        ),
        (
            good.replacen("[\"executable\",\"", "[\"executable\",\"0", 1),
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
            "does not match its checksum",
        ),
        (
            sealed(&good.replacen("\"iteration\":4", "\"iteration\":3", 1)),
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

/// A checkpoint's text with its header's checksum made that of its (edited) state: what the
/// path tracer's own checks see past the library's.
fn sealed(text: &str) -> String {
    let (header, state) = text.split_once('\n').unwrap();
    let mut header: serde_json::Value = serde_json::from_str(header).unwrap();
    let sum = pathtracer::run::checkpoint::fnv1a(state.as_bytes());
    header["checksum"] = format!("{sum:016x}").into();
    format!("{header}\n{state}")
}
