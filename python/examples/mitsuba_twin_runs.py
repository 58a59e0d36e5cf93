"""The tasks' default method (``polished``) on their Mitsuba twins, through the Python package.

For each task and seed: the task's Mitsuba twin (mitsuba_twin.py, moved by the exporter),
the target rendered with the run's seed, and ``plateau_free.minimize(fun, start,
method="polished", sigma0, lr, samples, budget=samples x iterations, seed, bounds)`` with the
task's supplemental Table 1 row as the export gives it (``defaults``), every render with the
run's seed (the loss is a deterministic function of theta, zero at the target, as in our
renderer's runs). ``--scale`` and ``--budget-scale`` shrink the resolution and the budget
(the page says so).

    target/venv/bin/python python/examples/mitsuba_twin_runs.py --tasks cup,occlusion \\
        --seeds 0,1,2 --scale 0.5 --out docs/results/mitsuba-twins

writes ``OUT/<task>-seed-<k>.json`` (kept: a second call runs only what is missing) and the
page ``OUT.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

TASKS = ("cup", "shadow", "occlusion", "gi", "sort", "caustic")


def one_run(mi, task: str, seed: int, scale: float | None, budget_scale: float) -> dict[str, Any]:
    import tempfile

    import plateau_free

    import mitsuba_export as mx
    import mitsuba_twin as mt

    twin = mt.Twin(mi, task, scale=scale)
    d = twin.desc["defaults"]
    start = np.array(twin.theta, dtype=np.float64)
    with tempfile.TemporaryDirectory() as tmp:
        target = np.array(mx.run_export(task, tmp, "target", scale=scale)["theta"], dtype=np.float64)
    reference = twin.render(target, seed)
    budget = max(2 * int(d["samples"]), int(round(d["samples"] * d["iterations"] * budget_scale)))
    bounds = [(0.0, 1.0)] * len(start) if d["unit_box"] else None
    renders = 0
    t0 = time.perf_counter()

    def fun(X):
        nonlocal renders
        out = []
        for x in X:
            img = twin.render(x, seed)
            out.append(float(np.mean((img - reference) ** 2)))
            renders += 1
        return np.array(out)

    result = plateau_free.minimize(fun, start, method="polished", sigma0=float(d["sigma0"]),
                                   lr=float(d["lr"]), samples=int(d["samples"]), budget=budget,
                                   seed=seed, batched=True, bounds=bounds)
    seconds = time.perf_counter() - t0
    x = np.asarray(result.x, dtype=np.float64)
    return {
        "task": task, "seed": seed, "scale": scale or 1.0, "spp": twin.spp,
        "width": int(twin.desc["film"]["width"]), "height": int(twin.desc["film"]["height"]),
        "budget": budget, "paper_budget": int(d["samples"] * d["iterations"]), "nfev": int(result.nfev),
        "start_param_mse": float(np.mean((start - target) ** 2)),
        "param_mse": float(np.mean((x - target) ** 2)), "image_mse": float(result.fun),
        "start_image_mse": float(np.mean((twin.render(start, seed) - reference) ** 2)),
        "seconds": seconds, "seconds_per_render": seconds / max(renders, 1),
        "final_theta": x.tolist() if len(x) <= 10 else None,
        "optimiser": f"plateau-free {plateau_free.__version__}",
    }


def page(rows: list[dict[str, Any]], args: argparse.Namespace, missing: list[str]) -> str:
    lines = [
        "# The tasks' default method on their Mitsuba twins",
        "",
        "Written by `target/venv/bin/python python/examples/mitsuba_twin_runs.py "
        + " ".join(sys.argv[1:]) + "` (docs/mitsuba.md, \"Every task on Mitsuba\").",
        "Each task's scene is its export (`pathtracer export`), moved at every render by the",
        "exporter (python/examples/mitsuba_twin.py); the optimiser is the Python package's",
        "`minimize(method=\"polished\")` with the task's supplemental Table 1 row, from the task's",
        "start, every render with the run's seed.",
        "",
        f"**Reduced** from the paper's settings where stated: resolution times {args.scale or 1.0}, "
        f"budget times {args.budget_scale} (the column `budget` against `paper budget`), to fit the "
        f"2 shared cores of this machine.",
        "",
        "| task | seed | size | spp | budget | paper budget | start param MSE | final param MSE | "
        "start image MSE | final image MSE | s / render |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['task']} | {r['seed']} | {r['width']}x{r['height']} | {r['spp']} | {r['budget']} "
            f"| {r['paper_budget']} | {r['start_param_mse']:.3e} | {r['param_mse']:.3e} "
            f"| {r['start_image_mse']:.3e} | {r['image_mse']:.3e} | {r['seconds_per_render']:.3f} |")
    lines += ["", f"Not run: {', '.join(missing) or 'none'}. TEXTURE has no twin (its 49,152 "
              "parameters do not fit the exporter's command line)."]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True)
    p.add_argument("--tasks", default=",".join(TASKS))
    p.add_argument("--seeds", default="0,1,2")
    p.add_argument("--scale", type=float, default=None)
    p.add_argument("--budget-scale", type=float, default=1.0)
    p.add_argument("--stop-at", default=None, help="HH:MM (UTC): start no run after this time")
    p.add_argument("--page-only", action="store_true")
    args = p.parse_args(argv)
    tasks = [t for t in args.tasks.split(",") if t]
    if not tasks or any(t not in TASKS for t in tasks):
        p.error(f"--tasks: {args.tasks!r}; allowed: {', '.join(TASKS)}")
    seeds = [int(s) for s in args.seeds.split(",") if s]
    if not 0 < args.budget_scale <= 1:
        p.error(f"--budget-scale: {args.budget_scale}; allowed: a number > 0 and <= 1")
    from mitsuba_scene import load_mitsuba

    mi = load_mitsuba()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows, missing = [], []
    for task in tasks:
        for seed in seeds:
            path = out / f"{task}-seed-{seed}.json"
            late = args.stop_at and time.strftime("%H:%M", time.gmtime()) >= args.stop_at
            if not path.exists() and not args.page_only and not late:
                row = one_run(mi, task, seed, args.scale, args.budget_scale)
                path.write_text(json.dumps(row, indent=1) + "\n")
                print(f"{task} seed {seed}: param MSE {row['start_param_mse']:.3e} -> {row['param_mse']:.3e} "
                      f"({row['seconds']:.0f} s)", flush=True)
            if path.exists():
                rows.append(json.loads(path.read_text()))
            else:
                missing.append(f"{task} seed {seed}")
    page_path = out.parent / f"{out.name}.md"
    page_path.write_text(page(rows, args, missing) + "\n")
    print(page_path)


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    main()
