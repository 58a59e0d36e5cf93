"""The every-task page (studies/mitsuba/tasks_page.py) from small fake results.

No mitsuba and no renderer: the page reads committed runs only, and the paper's numbers are
given here as `pathtracer export` would state them.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))  # `studies`

from studies.mitsuba import tasks_page as tp  # noqa: E402

PAPER = {"cup": {"image_mse": 4.92e-6, "param_mse": 4.18e-7, "seconds_per_iteration": 0.1,
                 "mitsuba_image_mse": 5.49e-3, "mitsuba_param_mse": 7.5e-2}}


def write_json(path: Path, value: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(value))


def fake_results(root: Path) -> Path:
    results = root / "docs" / "results"
    # Ours on our renderer: CUP seeds 0 and 2 (seed 0 lives in cup/), seed 1 not run.
    for seed, folder, pm in ((0, "cup", 2.5e-17), (2, "cup-seed2", 3.0e-3)):
        write_json(results / "seeds-polished" / folder / "summary.json", {
            "width": 128, "height": 96, "spp": 16, "evaluations": 800, "seconds_total": 80.0,
            "initial_param_mse": 0.0625, "param_mse": pm, "initial_image_mse": 1.4e-4, "image_mse": 0.0})
    (results / "seeds-polished" / "cup" / "final.png").write_bytes(b"png")
    # Ours on Mitsuba: CUP seed 0 at half resolution and the paper's budget, seed 1 reduced.
    for seed, budget in ((0, 800), (1, 400)):
        write_json(results / "mitsuba-twins" / f"cup-seed-{seed}.json", {
            "task": "cup", "seed": seed, "scale": 0.5, "width": 64, "height": 48, "spp": 16, "budget": budget,
            "paper_budget": 800, "nfev": budget, "start_param_mse": 0.0625, "param_mse": 1e-16,
            "start_image_mse": 1.45e-4, "image_mse": 0.0, "seconds_per_render": 0.0934})
    (results / "mitsuba-twins" / "cup-seed-0-final.png").write_bytes(b"png")
    return results


def test_numbers_are_formatted_and_missing_ones_say_so():
    assert tp.fmt(0.0) == "0" and tp.fmt(1.5e-7) == "1.50e-07" and tp.fmt("0.3") == "3.00e-01"
    assert tp.fmt(None) == "not measured" and tp.fmt("") == "not measured" and tp.fmt(math.nan) == "not measured"
    assert tp.fmt("abc", "not run") == "not run"
    assert tp.fmt_seconds(0.18712) == "0.187" and tp.fmt_seconds(12.34) == "12.3" and tp.fmt_seconds(None) == "not measured"


def test_without_mitsubas_gradient_runs_that_column_is_not_measured(tmp_path):
    results = fake_results(tmp_path)
    text = tp.build_page(results, results, PAPER, "CMD")
    assert "Written by `CMD`" in text
    row = next(line for line in text.splitlines() if line.startswith("| CUP |"))
    assert row == ("| CUP | 4.18e-07 | 7.50e-02 | 2.50e-17, not run, 3.00e-03 | 1.00e-16, 1.00e-16, not run "
                   "| not measured, not measured, not measured |")
    # Ours: 1 of the 2 seeds run reach the paper's 4.18e-7 (in bold); 80 s over 800 renders.
    assert "- ours on our renderer: 1 of 2 seeds at or below the paper's parameter MSE (1 not run)" in text
    assert "| ours, our renderer | 0 | 128x96, 16 spp, 800 renders | 6.25e-02 | **2.50e-17** | 1.40e-04 | 0 | 0.1 |" in text
    assert "| ours, our renderer | 2 | 128x96, 16 spp, 800 renders | 6.25e-02 | 3.00e-03 |" in text
    assert "| ours, our renderer | 1 | not run |" in text
    # The twin: seed 1 ran on half the paper's budget, and says so.
    assert "| ours, Mitsuba | 0 | 64x48, 16 spp, 800 renders of the paper's 800 (reduced) |" in text
    assert "| ours, Mitsuba | 1 | 64x48, 16 spp, 400 renders of the paper's 800 (reduced) |" in text
    assert "- Mitsuba's gradient on Mitsuba: not measured" in text
    assert "| Mitsuba's gradient, Mitsuba | 2 | not measured |" in text
    # Images that exist are shown, the others are a dash; TEXTURE has no paper row.
    assert "| 0 | - | ![](seeds-polished/cup/final.png) | - | ![](mitsuba-twins/cup-seed-0-final.png) |" in text
    assert "| TEXTURE | - | - | not run, not run, not run |" in text
    assert "Paper: no Table 2 row" in text


def test_mitsubas_gradient_runs_are_read_and_missing_columns_are_not_measured(tmp_path):
    results = fake_results(tmp_path)
    csv_path = results / "mitsuba-gradient" / "runs.csv"
    csv_path.parent.mkdir(parents=True)
    # No seconds_per_iteration and no start_image_mse column; seed 1's final MSE is empty.
    csv_path.write_text("task,seed,integrator,iterations,spp,scale,lr,start_param_mse,final_param_mse,final_image_mse\n"
                        "cup,0,prb_projective,50,16,5.000000e-01,1.000000e-02,0.0625,0.0625,1.4e-4\n"
                        "cup,1,prb_projective,50,16,0.5,0.01,0.0625,,\n"
                        "CUP,2,prb_projective,50,16,0.5,0.01,0.0625,2e-7,3e-9\n")
    text = tp.build_page(results, results, PAPER, "CMD")
    row = next(line for line in text.splitlines() if line.startswith("| CUP |"))
    assert row.endswith("| 6.25e-02, not measured, 2.00e-07 |")
    assert ("| Mitsuba's gradient, Mitsuba | 0 | integrator prb_projective, iterations 50, spp 16, scale 0.5, "
            "lr 0.01 | 6.25e-02 | 6.25e-02 | not measured | 1.40e-04 | not measured |") in text
    assert "| Mitsuba's gradient, Mitsuba | 2 | integrator prb_projective" in text and "| **2.00e-07** |" in text
    assert "- Mitsuba's gradient on Mitsuba: 1 of 2 seeds at or below the paper's parameter MSE (1 not measured)" in text


@pytest.mark.parametrize("header", ["task,seed\n", "seed,final_param_mse\n0,1e-3\n", ""])
def test_a_gradient_file_without_its_key_columns_measures_nothing(tmp_path, header):
    results = fake_results(tmp_path)
    path = results / "mitsuba-gradient" / "runs.csv"
    path.parent.mkdir(parents=True)
    path.write_text(header)
    assert tp.read_gradient(results) == {}
