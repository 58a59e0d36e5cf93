"""Every task on both renderers, beside the paper's numbers: docs/results/mitsuba-tasks.md.

    target/venv/bin/python -m studies mitsuba-tasks

reads only the runs of other studies (it renders nothing and needs no mitsuba); their commands
make them, and the repository does not keep them:

* the paper's numbers (Fischer & Ritschel, "Plateau-reduced Differentiable Path Tracing",
  CVPR 2023: main paper Table 2, plateau and Mitsuba 3 columns; Table 3, GPU seconds an
  iteration) from ``pathtracer export TASK`` (``"paper"``, from the task table in
  examples/pathtracer/src/tasks/mod.rs, so they are typed once);
* ours on our renderer: ``docs/results/seeds-polished/<task>[-seed<k>]/summary.json``
  (``pathtracer seeds``, the tasks' default method, polished);
* ours on Mitsuba: ``docs/results/mitsuba-twins/<task>-seed-<k>.json``
  (twins.py) and, for SHADOW, ``docs/results/mitsuba-polished/seed-<k>/summary.json``
  (optimize.py, full resolution);
* Mitsuba's own gradient on Mitsuba: ``docs/results/mitsuba-gradient/runs.csv`` (columns task,
  seed, integrator, iterations, spp, scale, lr, start_param_mse, final_param_mse,
  start_image_mse, final_image_mse, seconds_per_iteration); a missing file, row or column is
  "not measured".

Seeds 0-2 of every task; what is missing says so. ``--root`` is the repository (default: this
clone), ``--out`` the page.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any, Optional

from studies import _page

HERE = Path(__file__).resolve().parent
TASKS = ("cup", "shadow", "occlusion", "gi", "sort", "caustic", "texture")
SEEDS = (0, 1, 2)
NOT_MEASURED = "not measured"
NOT_RUN = "not run"
GRADIENT_COLUMNS = ("task", "seed", "integrator", "iterations", "spp", "scale", "lr", "start_param_mse",
                    "final_param_mse", "start_image_mse", "final_image_mse", "seconds_per_iteration")

Row = dict[str, Any]


def fmt(v: Any, missing: str = NOT_MEASURED) -> str:
    """A number as the page writes it: three significant digits in e-notation, 0 as 0."""
    if v is None or v == "":
        return missing
    try:
        x = float(v)
    except (TypeError, ValueError):
        return missing
    if math.isnan(x):
        return missing
    return "0" if x == 0 else f"{x:.2e}"


def fmt_seconds(v: Any, missing: str = NOT_MEASURED) -> str:
    """Seconds to three significant digits (0.187, 1.54, 12.3)."""
    x = _number(v)
    return missing if x is None else f"{x:.3g}"


def _number(v: Any) -> Optional[float]:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return None if math.isnan(x) else x


def _short(v: Any) -> str:
    """A setting as written briefly: a number in its shortest form (2.500000e-01 -> 0.25)."""
    x = _number(v)
    return str(v).strip() if x is None else f"{x:g}"


def _json(path: Path) -> Optional[dict[str, Any]]:
    return json.loads(path.read_text()) if path.is_file() else None


def ours_on_ours(results: Path, task: str, seed: int) -> Optional[Row]:
    """A polished run on our renderer (``pathtracer seeds``: seed 0 in ``<task>/``)."""
    d = results / "seeds-polished" / (task if seed == 0 else f"{task}-seed{seed}")
    s = _json(d / "summary.json")
    if s is None:
        return None
    renders = _number(s.get("evaluations"))
    total = _number(s.get("seconds_total"))
    return {
        "settings": f"{s.get('width')}x{s.get('height')}, {s.get('spp')} spp, {s.get('evaluations')} renders",
        "start_param_mse": s.get("initial_param_mse"), "param_mse": s.get("param_mse"),
        "start_image_mse": s.get("initial_image_mse"), "image_mse": s.get("image_mse"),
        "seconds_per_render": total / renders if total is not None and renders else None,
        "final_png": d / "final.png", "target_png": d / "target.png",
    }


def ours_on_mitsuba(results: Path, task: str, seed: int) -> Optional[Row]:
    """A polished run on the task's Mitsuba twin (SHADOW: its full-resolution study)."""
    if task == "shadow":
        d = results / "mitsuba-polished" / f"seed-{seed}"
        s = _json(d / "summary.json")
        if s is None:
            return None
        return {
            "settings": f"{s.get('width')}x{s.get('height')}, {s.get('spp')} spp, {s.get('nfev')} renders",
            "start_param_mse": s.get("initial_param_mse"), "param_mse": s.get("param_mse"),
            "start_image_mse": s.get("initial_image_mse"), "image_mse": s.get("image_mse"),
            "seconds_per_render": s.get("seconds_per_evaluation"),
            "final_png": d / "final.png", "target_png": d / "target.png",
        }
    d = results / "mitsuba-twins"
    s = _json(d / f"{task}-seed-{seed}.json")
    if s is None:
        return None
    reduced = s.get("budget") != s.get("paper_budget") or s.get("scale") != 1.0
    return {
        "settings": (f"{s.get('width')}x{s.get('height')}, {s.get('spp')} spp, {s.get('nfev')} renders"
                     f" of the paper's {s.get('paper_budget')}" + (" (reduced)" if reduced else "")),
        "start_param_mse": s.get("start_param_mse"), "param_mse": s.get("param_mse"),
        "start_image_mse": s.get("start_image_mse"), "image_mse": s.get("image_mse"),
        "seconds_per_render": s.get("seconds_per_render"),
        "final_png": d / f"{task}-seed-{seed}-final.png", "target_png": d / f"{task}-seed-{seed}-target.png",
    }


def read_gradient(results: Path) -> dict[tuple[str, int], Row]:
    """Mitsuba's gradient runs by (task, seed); empty if the file is missing."""
    path = results / "mitsuba-gradient" / "runs.csv"
    if not path.is_file():
        return {}
    runs: dict[tuple[str, int], Row] = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            try:
                key = (str(r["task"]).strip().lower(), int(r["seed"]))
            except (KeyError, TypeError, ValueError):
                continue
            settings = ", ".join(f"{k} {_short(r[k])}" for k in ("integrator", "iterations", "spp", "scale", "lr")
                                 if r.get(k) not in (None, ""))
            runs[key] = {
                "settings": settings or NOT_MEASURED,
                "start_param_mse": r.get("start_param_mse"), "param_mse": r.get("final_param_mse"),
                "start_image_mse": r.get("start_image_mse"), "image_mse": r.get("final_image_mse"),
                "seconds_per_iteration": r.get("seconds_per_iteration"),
            }
    return runs


def paper_from_export(task: str) -> Optional[dict[str, float]]:
    """The paper's numbers for ``task`` as ``pathtracer export`` states them (None: TEXTURE)."""
    from studies.mitsuba import _export as mx

    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([mx.pathtracer_binary(), "export", task, "--scale", "0.125", "--spp", "1", "--out", tmp],
                       check=True, stdout=subprocess.DEVNULL)
        paper: Optional[dict[str, float]] = json.loads((Path(tmp) / "scene.json").read_text()).get("paper")
        return paper


def _reached(value: Any, goal: Optional[float]) -> Optional[bool]:
    x = _number(value)
    return None if x is None or goal is None else x <= goal


def count_line(label: str, rows: list[Optional[Row]], goal: Optional[float], what: str) -> str:
    """"k of n" seeds at or below the paper's parameter MSE, with the seeds not measured."""
    ran = [r for r in rows if r is not None and _number(r.get("param_mse")) is not None]
    if not ran:
        return f"{label}: {what}"
    if goal is None:
        return f"{label}: {len(ran)} of {len(rows)} seeds measured (the paper has no number)"
    hit = sum(1 for r in ran if _reached(r["param_mse"], goal))
    rest = len(rows) - len(ran)
    return (f"{label}: {hit} of {len(ran)} seeds at or below the paper's parameter MSE"
            + (f" ({rest} {what})" if rest else ""))


def _link(page_dir: Path, path: Any) -> str:
    if not isinstance(path, Path) or not path.is_file():
        return "-"
    return f"![]({os.path.relpath(path, page_dir)})"


def task_section(task: str, paper: Optional[dict[str, float]], results: Path, page_dir: Path,
                 gradient: dict[tuple[str, int], Row]) -> list[str]:
    goal = _number(paper.get("param_mse")) if paper else None
    ours = [ours_on_ours(results, task, s) for s in SEEDS]
    twin = [ours_on_mitsuba(results, task, s) for s in SEEDS]
    grad = [gradient.get((task, s)) for s in SEEDS]
    lines = [f"## {task.upper()}", ""]
    if paper:
        lines.append(
            f"Paper (Table 2): plateau image / parameter MSE {fmt(paper.get('image_mse'))} / "
            f"{fmt(paper.get('param_mse'))} ({fmt_seconds(paper.get('seconds_per_iteration'))} GPU s an iteration, "
            f"Table 3); Mitsuba 3 {fmt(paper.get('mitsuba_image_mse'))} / {fmt(paper.get('mitsuba_param_mse'))}.")
    else:
        lines.append("Paper: no Table 2 row (TEXTURE is the supplemental's Sec. 3).")
    lines += ["",
              "- " + count_line("ours on our renderer", ours, goal, NOT_RUN),
              "- " + count_line("ours on Mitsuba", twin, goal, NOT_RUN),
              "- " + count_line("Mitsuba's gradient on Mitsuba", grad, goal, NOT_MEASURED),
              "",
              "| renderer, method | seed | settings | start param MSE | final param MSE | start image MSE "
              "| final image MSE | s / render |",
              "|---|---|---|---|---|---|---|---|"]
    for label, rows, missing in (("ours, our renderer", ours, NOT_RUN), ("ours, Mitsuba", twin, NOT_RUN),
                                 ("Mitsuba's gradient, Mitsuba", grad, NOT_MEASURED)):
        for seed, r in zip(SEEDS, rows):
            if r is None:
                lines.append(f"| {label} | {seed} | {missing} | | | | | |")
                continue
            final = fmt(r.get("param_mse"), missing)
            if _reached(r.get("param_mse"), goal):
                final = f"**{final}**"
            if "seconds_per_iteration" in r:
                speed = fmt_seconds(r.get("seconds_per_iteration"))
                speed = speed if speed == NOT_MEASURED else f"{speed} (an iteration: render and gradient)"
            else:
                speed = fmt_seconds(r.get("seconds_per_render"))
            lines.append(f"| {label} | {seed} | {r['settings']} | {fmt(r.get('start_param_mse'), missing)} | "
                         f"{final} | {fmt(r.get('start_image_mse'), missing)} | {fmt(r.get('image_mse'), missing)} "
                         f"| {speed} |")
    images = [(s, o, t) for s, o, t in zip(SEEDS, ours, twin) if o is not None or t is not None]
    if images:
        lines += ["", "| seed | target (our renderer) | final, our renderer | target (Mitsuba) | final, Mitsuba |",
                  "|---|---|---|---|---|"]
        for s, o, t in images:
            lines.append(f"| {s} | {_link(page_dir, (o or {}).get('target_png'))} | "
                         f"{_link(page_dir, (o or {}).get('final_png'))} | "
                         f"{_link(page_dir, (t or {}).get('target_png'))} | {_link(page_dir, (t or {}).get('final_png'))} |")
    return lines + [""]


def build_page(results: Path, page_dir: Path, papers: dict[str, Optional[dict[str, float]]],
               command: str) -> str:
    """The page from ``results`` (a docs/results folder) and the paper's numbers per task."""
    gradient = read_gradient(results)
    lines = [
        "# Every task on both renderers, beside the paper",
        "",
        f"Written by `{command}` from the runs of other studies, named below (it renders nothing; "
        "their commands make them, and the repository does not keep them). The paper: Fischer & Ritschel,",
        "\"Plateau-reduced Differentiable Path Tracing\", CVPR 2023, main paper Table 2 (final image /",
        "parameter MSE of its plateau-reduced gradient and of Mitsuba 3's) and Table 3 (GPU seconds an",
        "iteration), as `pathtracer export` states them. Ours on our renderer: the tasks' default method",
        "(polished) at the paper's settings, `docs/results/seeds-polished/` (`pathtracer seeds`). Ours on",
        "Mitsuba: the same method on the task's Mitsuba twin, `docs/results/mitsuba-twins.md` (SHADOW: its",
        "full-resolution study, `docs/results/mitsuba-polished.md`); where the settings say \"reduced\", at",
        "a smaller resolution or budget than the paper's, to fit the 2 shared cores. Mitsuba's gradient:",
        "`docs/results/mitsuba-gradient/runs.csv` (where it works and where it fails, and why:",
        "[mitsuba-gradient.md](mitsuba-gradient.md)). A final parameter MSE in **bold** is at or below the",
        "paper's (plateau). Seconds per render: wall-clock over the run's renders on this machine (2",
        "shared cores), Mitsuba's gradient per iteration. Seeds 0-2.",
        "",
        "| task | paper: plateau param MSE | paper: Mitsuba 3 param MSE | ours, our renderer: final param MSE "
        "(seeds 0-2) | ours, Mitsuba | Mitsuba's gradient, Mitsuba |",
        "|---|---|---|---|---|---|",
    ]
    sections: list[str] = []
    for task in TASKS:
        paper = papers.get(task)
        cells = []
        for rows, missing in (([ours_on_ours(results, task, s) for s in SEEDS], NOT_RUN),
                              ([ours_on_mitsuba(results, task, s) for s in SEEDS], NOT_RUN),
                              ([gradient.get((task, s)) for s in SEEDS], NOT_MEASURED)):
            cells.append(", ".join(fmt(r.get("param_mse"), missing) if r else missing for r in rows))
        lines.append(f"| {task.upper()} | {fmt((paper or {}).get('param_mse'), '-')} | "
                     f"{fmt((paper or {}).get('mitsuba_param_mse'), '-')} | " + " | ".join(cells) + " |")
        sections += task_section(task, paper, results, page_dir, gradient)
    return "\n".join(lines + [""] + sections)


def main(argv: Optional[list[str]] = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--root", default=str(HERE.parent.parent), help="the repository (default: this clone)")
    p.add_argument("--out", default=None, help="the page (default: ROOT/docs/results/mitsuba-tasks.md)")
    args = p.parse_args(argv)
    root = Path(args.root)
    results = root / "docs" / "results"
    out = Path(args.out) if args.out else results / "mitsuba-tasks.md"
    papers = {t: paper_from_export(t) for t in TASKS}
    command = "target/venv/bin/python -m studies mitsuba-tasks" + "".join(
        f" {a}" for a in (argv if argv is not None else sys.argv[1:]))
    _page.write(out, build_page(results, out.parent.resolve(), papers, command))
    print(out)


if __name__ == "__main__":
    main()
