"""Tasks on Mitsuba 3 (studies/mitsuba/optimize.py): SHADOW's short runs, the scene, the
hints; another task (CUP) on its twin through the same command.

Needs mitsuba in the interpreter that runs pytest: `scripts/install-mitsuba VENV` installs it.
Without it the Mitsuba tests are skipped, or fail when PLATEAU_FREE_REQUIRE_MITSUBA=1 (the test
command sets it, so that a broken install cannot pass as a skip).
"""

from __future__ import annotations

import csv
import importlib.util
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

import plateau_free

REPO = Path(__file__).resolve().parents[2]
# The study runs from the repository as `python -m studies mitsuba-optimize`.
STUDY = ["-m", "studies", "mitsuba-optimize"]
sys.path.insert(0, str(REPO))

HAVE_MITSUBA = importlib.util.find_spec("mitsuba") is not None
REQUIRE = os.environ.get("PLATEAU_FREE_REQUIRE_MITSUBA") == "1"

needs_mitsuba = pytest.mark.skipif(
    not HAVE_MITSUBA and not REQUIRE,
    reason="mitsuba is not installed (scripts/install-mitsuba; PLATEAU_FREE_REQUIRE_MITSUBA=1 makes this a failure)",
)


def test_without_mitsuba_the_example_says_how_to_install_it():
    code = (
        "import sys, runpy; sys.modules['mitsuba'] = None; "
        "sys.argv = ['studies', 'mitsuba-optimize', '--out', 'unused']; runpy.run_module('studies', run_name='__main__')"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=REPO)
    assert p.returncode != 0
    lines = [line for line in p.stderr.strip().splitlines() if line.strip()]
    assert len(lines) == 1, p.stderr
    assert "scripts/install-mitsuba" in lines[0]


def test_without_plateau_free_the_example_says_how_to_install_it():
    # The example runs the package itself (no stand-in): without it, one line saying how to get it.
    code = (
        "import sys, runpy; sys.modules['plateau_free'] = None; "
        "sys.argv = ['studies', 'mitsuba-optimize', '--out', 'unused']; runpy.run_module('studies', run_name='__main__')"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=REPO)
    assert p.returncode != 0
    lines = [line for line in p.stderr.strip().splitlines() if line.strip()]
    assert len(lines) == 1, p.stderr
    assert "pip install plateau-free" in lines[0] and "pip install ./python" in lines[0]


@needs_mitsuba
def test_scene_is_the_task_and_renders_deterministically_per_seed():
    from studies.mitsuba import _scene as ms

    mi = ms.load_mitsuba()
    scene = ms.ShadowScene(mi, spp=8, scale=0.25)
    target = scene.render(ms.TARGET, 0)
    assert target.shape == (48, 64, 3)
    # The same seed renders the same image (the common random numbers the loss relies on).
    assert ms.image_mse(scene.render(ms.TARGET, 0), target) == 0.0
    # Start and target differ only by where the shadow lies: a few percent of the image.
    start = scene.render(ms.START, 0)
    assert 1e-3 < ms.image_mse(start, target) < 5e-2
    # The shadows of start and target do not overlap: moving the sphere a little moves its
    # shadow but leaves the loss nearly unchanged (the plateau).
    nudged = scene.render((ms.START[0] + 0.05, ms.START[1] - 0.05), 0)
    assert abs(ms.image_mse(nudged, target) - ms.image_mse(start, target)) < 0.05 * ms.image_mse(start, target)
    assert ms.param_mse(ms.START) == 1.625


def short_search_run(tmp_path: Path, method: str) -> tuple[dict, list[dict]]:
    """A short `--method adaptive|polished` run (2 x 15 = 30 renders at 32x24, seed 4): checks the
    files and the summary's finite numbers; returns the summary and the history's rows."""
    out = tmp_path / method
    cmd = [sys.executable, *STUDY, "--method", method, "--out", str(out), "--iterations", "15",
           "--scale", "0.125", "--spp", "8", "--eval-every", "2", "--seed", "4", "--progress", "0"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=900, cwd=REPO)
    assert p.returncode == 0, p.stderr[-3000:]
    for f in ("target.png", "initial.png", "final.png", "convergence.png", "history.csv", "summary.json"):
        assert (out / f).is_file(), f
    assert not (out / "ad_history.csv").exists()  # these methods run no Mitsuba AD
    s = json.loads((out / "summary.json").read_text())
    assert s["method"] == method and s["seed"] == 4 and s["budget"] == 30
    assert s["optimiser"] == f"plateau-free {plateau_free.__version__}"
    for k in ("param_mse", "image_mse", "seconds_per_iteration", "seconds_per_evaluation", "best_loss"):
        assert math.isfinite(s[k]), k
    return s, list(csv.DictReader(open(out / "history.csv")))


def assert_returns_its_best_render(s: dict, rows: list[dict]) -> None:
    """The rows follow the best point so far: its loss never grows, and the run returns it, the
    render with the least image MSE (every render uses the run's seed, so rendering it again
    gives the same image and loss)."""
    best = [float(r["best_loss"]) for r in rows]
    assert all(b <= a for a, b in zip(best, best[1:]))
    assert s["best_loss"] == pytest.approx(best[-1], rel=1e-6)
    assert s["image_mse"] == pytest.approx(s["best_loss"], rel=1e-6)
    assert s["final_theta"] == pytest.approx([float(rows[-1]["theta0"]), float(rows[-1]["theta1"])], rel=1e-6)


@needs_mitsuba
def test_short_run_writes_everything(tmp_path):
    out = tmp_path / "run"
    cmd = [sys.executable, *STUDY, "--method", "plateau", "--out", str(out), "--iterations", "4",
           "--scale", "0.125", "--ad-iterations", "1", "--eval-every", "2", "--seed", "3"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=900, cwd=REPO)
    assert p.returncode == 0, p.stderr[-3000:]
    for f in ("target.png", "initial.png", "final.png", "ad_final.png", "convergence.png",
              "history.csv", "ad_history.csv", "summary.json"):
        assert (out / f).is_file(), f
    s = json.loads((out / "summary.json").read_text())
    for k in ("param_mse", "image_mse", "seconds_per_iteration", "mitsuba_ad_param_mse"):
        assert math.isfinite(s[k]), k
    # 4 iterations of N = 2 renders; plateau_free.minimize renders once more at the end for result.fun.
    assert s["seed"] == 3 and s["nit"] == 4 and s["nfev"] in (8, 9)
    assert s["optimiser"] == f"plateau-free {plateau_free.__version__}"
    assert s["mitsuba_ad_iterations"] == 1 and s["mitsuba_ad_integrator"] == "direct_projective"
    assert s["width"] == 32 and s["height"] == 24
    rows = list(csv.DictReader(open(out / "history.csv")))
    assert [int(r["iteration"]) for r in rows] == [0, 1, 2, 3]
    # Four steps of LR 0.02 move theta at most 0.08 per coordinate.
    assert abs(float(rows[-1]["theta0"]) + 0.5) <= 0.081 and abs(float(rows[-1]["theta1"]) - 2.5) <= 0.081
    assert rows[0]["image_mse"] and rows[2]["image_mse"] and not rows[1]["image_mse"]


@needs_mitsuba
def test_short_adaptive_run_writes_everything_and_returns_its_best_render(tmp_path):
    s, rows = short_search_run(tmp_path, "adaptive")
    assert 0 < s["nfev"] <= 30 and s["nit"] >= 2
    assert s["seconds_per_iteration"] >= s["seconds_per_evaluation"] > 0
    # Row 0 the start (rendered first and alone, so the result is never worse than it), then one
    # row per generation; the renders add up to nfev.
    assert [int(r["iteration"]) for r in rows] == list(range(s["nit"] + 1))
    assert int(rows[0]["population"]) == 1 and float(rows[0]["loss"]) == pytest.approx(s["initial_image_mse"], rel=1e-6)
    assert int(rows[-1]["renders"]) == s["nfev"] == sum(int(r["population"]) for r in rows)
    assert_returns_its_best_render(s, rows)
    assert s["best_loss"] <= s["initial_image_mse"]
    assert s["param_mse"] == pytest.approx(sum((a - b) ** 2 for a, b in zip(s["final_theta"], (-1.5, 1.0))) / 2)
    # The image error of the best point every eval_every x N = 4 renders (and last).
    assert rows[0]["image_mse"] and rows[-1]["image_mse"]
    assert float(rows[-1]["image_mse"]) == pytest.approx(s["image_mse"], rel=1e-6)


@needs_mitsuba
def test_short_polished_run_is_the_loop_then_the_adaptive_search(tmp_path):
    # Budget N x iterations = 2 x 15 = 30 renders at 32x24: the loop gets 30 - floor(30 / 4) = 23,
    # of which it renders 22: the start, 10 iterations of 2 renders and its final render; the
    # adaptive search the other 8.
    s, rows = short_search_run(tmp_path, "polished")
    assert s["polish"] == 0.25
    # The paper loop's settings (Table 1), as the paper-loop runs record them.
    assert (s["samples"], s["lr"], s["sigma0"], s["anneal"], s["sampling"]) == (2, 0.02, 0.5, "paper", "radial")
    assert s["nfev"] == 30 and s["loop_renders"] == 22
    phases = [r["phase"] for r in rows]
    loop = phases.count("loop")
    assert loop == 11 and phases == ["start"] + ["loop"] * loop + ["polish"] * (len(rows) - loop - 1)
    assert len(rows) > loop + 1
    assert [int(r["population"]) for r in rows[: loop + 1]] == [1] + [2] * 10 + [1]
    assert int(rows[loop]["renders"]) == 22
    assert int(rows[-1]["renders"]) == s["nfev"] == sum(int(r["population"]) for r in rows)
    assert s["nit"] == len(rows) - 2  # the loop's 10 iterations, then one per generation
    assert_returns_its_best_render(s, rows)


def test_polish_is_an_option_of_method_polished(tmp_path):
    for extra in (["--method", "adaptive", "--polish", "0.5"], ["--method", "polished", "--polish", "1"]):
        p = subprocess.run([sys.executable, *STUDY, *extra, "--out", str(tmp_path / "x")],
                           capture_output=True, text=True, timeout=300, cwd=REPO)
        assert p.returncode == 2 and "--polish" in p.stderr, p.stderr
    assert not (tmp_path / "x").exists()


def test_a_folder_holds_one_methods_runs(tmp_path):
    out = tmp_path / "study"
    (out / "seed-0").mkdir(parents=True)
    (out / "seed-0" / "summary.json").write_text(json.dumps({"seed": 0, "param_mse": 1.0}))  # a paper-loop run
    p = subprocess.run([sys.executable, *STUDY, "--method", "adaptive", "--seeds", "1", "--out", str(out)],
                       capture_output=True, text=True, timeout=300, cwd=REPO)
    assert p.returncode != 0
    assert "not 'adaptive'" in p.stderr and "own --out" in p.stderr


@pytest.mark.parametrize("method", ["adaptive", "polished"])
def test_adaptive_page_compares_per_seed_and_names_seeds_not_run(tmp_path, method):
    """--page-only with --method adaptive (or polished): the page from the runs alone (no
    mitsuba needed)."""
    out, paper = tmp_path / "mitsuba-adaptive", tmp_path / "mitsuba"
    hist = "iteration,population,renders,sigma,loss,best_loss,param_mse,image_mse,seconds,theta0,theta1\n"
    for s, pm in ((0, 1e-5), (2, 3.0)):
        d = out / f"seed-{s}"
        d.mkdir(parents=True)
        extra = {"polish": 0.25, "loop_renders": 599, "lr": 0.02, "samples": 2} if method == "polished" else {}
        (d / "summary.json").write_text(json.dumps(extra | {
            "method": method, "seed": s, "budget": 800, "nit": 120, "nfev": 800, "restarts": 1,
            "param_mse": pm, "image_mse": 2e-5, "seconds_per_iteration": 6.0, "seconds_per_evaluation": 0.9,
            "load_average_at_start": 4.0, "spp": 32, "sigma0": 0.5, "crn": "fixed", "mitsuba_version": "3.9.1",
            "variant": "llvm_ad_rgb", "optimiser": "plateau-free 0.1.0"}))
        (d / "history.csv").write_text(hist + f"0,6,6,0.5,0.01,0.009,{pm},,1.0,-1.5,1.0\n")
    for s, pm in ((0, 2e-6), (1, 5.8), (2, 4e-5)):
        d = paper / f"seed-{s}"
        d.mkdir(parents=True)
        (d / "summary.json").write_text(json.dumps({"seed": s, "param_mse": pm, "seconds_per_iteration": 4.8,
                                                    "samples": 2}))
    page = tmp_path / "page.md"
    p = subprocess.run([sys.executable, *STUDY, "--method", method, "--seeds", "3", "--page-only",
                        "--out", str(out), "--plateau-runs", str(paper), "--page", str(page)],
                       capture_output=True, text=True, timeout=300, cwd=REPO)
    assert p.returncode == 0, p.stderr[-3000:]
    text = page.read_text()
    rows = {line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:-1]]
            for line in text.split("## Images")[0].splitlines() if line.startswith("| ") and line.split("|")[1].strip().isdigit()}
    assert rows["0"][0] == "1.00e-05" and rows["0"][8] == "2.00e-06"
    assert rows["1"][0] == "not run" and rows["1"][8] == "5.8"
    assert rows["2"][0] == "3" and rows["2"][2] == "120" and rows["2"][4] == "800"
    # Adaptive 1 of the 2 seeds run; the paper loop 2 of those 2, and 2 of 3 in all.
    assert f"**{method} 1 of 2** seeds run (not run: [1]); the paper's loop 2 of the same 2, 2 of 3 in all" in text
    assert f"--method {method} --seeds 3" in text
    if method == "polished":
        assert text.startswith("# SHADOW on Mitsuba 3: the paper's loop polished by the adaptive search")
        assert ('`plateau_free.minimize(fun, x0, method="polished", sigma0=0.5, lr=0.02, samples=2, budget=800, '
                'polish=0.25, seed=seed, batched=True)`') in text
        assert "on the first 0.75 of the renders (599, its final render included)" in text
        assert "| seed | polished: param MSE |" in text and "| seed | target | start | polished | paper loop |" in text
    else:
        assert "adaptive" in text.splitlines()[0] and "polished" not in text


@needs_mitsuba
def test_any_task_runs_with_the_default_method_on_its_twin(tmp_path):
    # --task cup: the tasks' default method (polished) on CUP's twin at 1/8 resolution and 2 %
    # of the paper's budget (16 renders): its JSON, final and target images; a second call keeps it.
    out = tmp_path / "cup"
    cmd = [sys.executable, *STUDY, "--task", "cup", "--scale", "0.125", "--budget-scale", "0.02",
           "--seed", "1", "--out", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600, cwd=REPO)
    assert p.returncode == 0, p.stderr[-3000:]
    row = json.loads((out / "cup-seed-1.json").read_text())
    assert (row["task"], row["method"], row["seed"], row["budget"], row["paper_budget"]) == ("cup", "polished", 1, 16, 800)
    assert row["nfev"] <= 16 and (row["width"], row["height"]) == (16, 12)
    assert row["start_param_mse"] == pytest.approx(0.0625)
    assert math.isfinite(row["param_mse"]) and math.isfinite(row["image_mse"])
    assert row["image_mse"] <= row["start_image_mse"]  # polished returns the best point it rendered
    assert (out / "cup-seed-1-final.png").is_file() and (out / "cup-seed-1-target.png").is_file()


@pytest.mark.parametrize("extra, name", [(["--ad-iterations", "3"], "--ad-iterations"),
                                         (["--budget-scale", "0"], "--budget-scale"),
                                         (["--scale", "-1"], "--scale")])
def test_shadow_only_and_bad_options_of_another_task_are_errors(tmp_path, extra, name):
    p = subprocess.run([sys.executable, *STUDY, "--task", "gi", *extra, "--out", str(tmp_path / "x")],
                       capture_output=True, text=True, timeout=300, cwd=REPO)
    assert p.returncode == 2 and name in p.stderr, p.stderr
    assert not (tmp_path / "x").exists()


def test_budget_scale_is_not_an_option_of_shadow(tmp_path):
    p = subprocess.run([sys.executable, *STUDY, "--budget-scale", "0.5", "--out", str(tmp_path / "x")],
                       capture_output=True, text=True, timeout=300, cwd=REPO)
    assert p.returncode == 2 and "--budget-scale" in p.stderr, p.stderr
