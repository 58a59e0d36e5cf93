//! The pages and exports the binary writes: the seeds page, the scene export.

use std::path::Path;

use crate::{fresh, refused_before_any_work, run};

#[test]
fn the_seeds_page_puts_studies_side_by_side() {
    // The paper loop's SHADOW and CUP runs of the seeds study (`tests/data/seeds-paper`, their
    // summaries and histories only): seeds 0-9 each, 8 and 2 of them at or below the paper's
    // parameter MSE, 7 and 7 at or below its image MSE.
    let committed = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/seeds-paper");
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
                .expect("the test data has this run");
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
