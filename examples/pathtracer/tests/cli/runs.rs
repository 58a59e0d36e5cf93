//! Runs to their end: where the polished method hands over, and what a run shows of its
//! progress off a terminal.

use std::path::Path;

use crate::{fresh, run};

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

/// Runs a tiny SHADOW optimisation with `more` arguments, its stderr a pipe (not a
/// terminal) and the plain progress line due every `seconds`; returns the exit code and the
/// progress lines on stderr.
fn progress_lines(tag: &str, more: &[&str], seconds: &str) -> (Option<i32>, Vec<String>) {
    let out = fresh(tag);
    let out_arg = out.display().to_string();
    let mut args = vec![
        "optimize",
        "shadow",
        "--scale",
        "0.125",
        "--spp",
        "2",
        "--iterations",
        "3",
        "--out",
        &out_arg,
    ];
    args.extend(more);
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_pathtracer"))
        .args(&args)
        .env("PATHTRACER_PROGRESS_SECONDS", seconds)
        .output()
        .expect("the binary runs");
    let _ = std::fs::remove_dir_all(&out);
    let lines = String::from_utf8_lossy(&output.stderr)
        .lines()
        .filter(|l| l.starts_with("shadow: iteration "))
        .map(String::from)
        .collect();
    (output.status.code(), lines)
}

/// Off a terminal, a run prints a plain line to stderr every few seconds (here after every
/// iteration) with the iteration, the renders, the best loss and the time: the paper's loop
/// counts to its iterations, the adaptive search to its renders (2 x 3 here). `--quiet`
/// prints none, nor does a run shorter than the spacing.
#[test]
fn off_a_terminal_a_plain_progress_line_goes_to_stderr() {
    let (code, lines) = progress_lines("progress-loop", &["--method", "plateau"], "0");
    assert_eq!(code, Some(0), "{lines:?}");
    assert_eq!(lines.len(), 3, "{lines:?}");
    for (k, line) in lines.iter().enumerate() {
        let head = format!(
            "shadow: iteration {}/3, renders {}, best loss ",
            k + 1,
            2 * (k + 1)
        );
        assert!(line.starts_with(&head), "{line:?} does not start {head:?}");
        assert!(
            line.ends_with(" s") && line.contains(", elapsed "),
            "{line:?}"
        );
    }
    let (code, lines) = progress_lines("progress-adaptive", &["--method", "adaptive"], "0");
    assert_eq!(code, Some(0), "{lines:?}");
    let last = lines.last().expect("a progress line");
    assert!(last.contains(", renders 6/6, best loss "), "{last:?}");
    for (more, seconds) in [(&["--quiet"][..], "0"), (&[][..], "3600")] {
        let (code, lines) = progress_lines("progress-none", more, seconds);
        assert_eq!(code, Some(0));
        assert!(lines.is_empty(), "{more:?} {seconds}: {lines:?}");
    }
}
