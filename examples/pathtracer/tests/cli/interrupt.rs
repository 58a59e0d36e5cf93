//! A real Ctrl-C (SIGINT): the run finishes its iteration, writes everything and resumes;
//! a second Ctrl-C exits at once.

use std::process::Command;

use crate::{fresh, results, run};

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
