"""The page of gradient.py: ``OUT.md`` from ``OUT/runs.csv`` and the runs' histories.

Every number on the page is read from the run files; the verdict per task follows from them
by the rules stated on the page (``verdict``).
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from studies import _page

# Main paper Table 2 (SPEC.md; the same numbers as PAPER in examples/pathtracer/src/tasks/mod.rs):
# (plateau-free image MSE, parameter MSE, Mitsuba 3 image MSE, parameter MSE). TEXTURE is the
# supplemental's and has no Mitsuba number.
PAPER = {
    "cup": (4.92e-6, 4.18e-7, 5.49e-3, 7.5e-2),
    "shadow": (1.74e-5, 1.81e-3, 1.64e-3, 5.06),
    "occlusion": (2.34e-4, 3.29e-3, 5.85e-2, 52.3),
    "gi": (5.07e-5, 8.71e-4, 3.78e-2, 3.87e-1),
    "sort": (3.81e-3, 4.19e-1, 1.18e-2, 6.64),
    "caustic": (1.89e-5, 9.76e-5, 3.12e-1, 8.50),
}
PAPER_ITERATIONS = {"cup": 400, "shadow": 400, "occlusion": 600, "gi": 500, "sort": 4000, "caustic": 500,
                    "texture": 4000}
TASKS = ("cup", "shadow", "occlusion", "gi", "sort", "caustic", "texture")


def _read(path: Path) -> list[dict[str, str]]:
    with open(path) as f:
        return list(csv.DictReader(f))


def history_stats(path: Path) -> dict[str, Any]:
    """Zero-gradient iterations, and (where theta is logged) how often -grad points to the target."""
    rows = _read(path)
    g = np.array([float(r["grad_norm"]) for r in rows])
    out: dict[str, Any] = {"zero": int(np.sum(g == 0.0)), "n": len(rows), "start_grad": g[0] if len(g) else None,
                           "toward": None}
    if rows and "theta0" in rows[0]:
        out["theta"] = [[float(r[k]) for k in r if k.startswith("theta")] for r in rows]
        out["grad"] = [[float(r[k]) for k in r if k.startswith("grad") and k != "grad_norm"] for r in rows]
    return out


def toward(stats: dict[str, Any], target: list[float]) -> float | None:
    """The fraction of iterations whose descent direction -grad points toward the target."""
    if "theta" not in stats:
        return None
    th, gr, t = np.array(stats["theta"]), np.array(stats["grad"]), np.array(target)
    dots = np.sum(-gr * (t - th), axis=1)
    live = np.linalg.norm(gr, axis=1) > 0
    return float(np.mean(dots[live] > 0)) if live.any() else 0.0


def verdict(runs: list[dict[str, str]], stats: list[dict[str, Any]], towards: list[float | None]) -> str:
    """Works (parameter MSE down 10x) on how many seeds, and why the others fail (the page's rules)."""
    ratios = [float(r["final_param_mse"]) / float(r["start_param_mse"]) for r in runs]
    bad = [i for i, q in enumerate(ratios) if q >= 0.1]
    n, k = len(runs), len(runs) - len(bad)
    if not bad:
        return f"works on {n} of {n} seeds (parameter MSE down at least 10x)"
    why = failure([ratios[i] for i in bad], [stats[i] for i in bad], [towards[i] for i in bad])
    return (f"works on {k} of {n} seeds; fails on {len(bad)}: {why}" if k else f"fails on {n} of {n} seeds: {why}")


def failure(ratios: list[float], stats: list[dict[str, Any]], towards: list[float | None]) -> str:
    """Why runs that did not get 10x closer failed, by the page's rules, in order."""
    zero = sum(s["zero"] for s in stats) / max(sum(s["n"] for s in stats), 1)
    known = [t for t in towards if t is not None]
    toward_mean = float(np.mean(known)) if known else None
    if zero > 0.5:
        return f"a plateau, the gradient is exactly zero in {100 * zero:.0f} % of the iterations"
    if toward_mean is not None and toward_mean < 0.4:
        return (f"misleading gradient (its descent direction points away from the target in "
                f"{100 * (1 - toward_mean):.0f} % of the iterations)")
    if toward_mean is not None and toward_mean <= 0.6:
        return (f"a plateau under noise (the gradient is not zero but points toward the target in "
                f"{100 * toward_mean:.0f} % of the iterations, a coin's toss)")
    if sum(q > 1.0 for q in ratios) * 2 > len(ratios):
        return "misleading gradient (parameter MSE grows on most of these seeds)"
    return "too slow (parameter MSE down less than 10x in the iterations run)"


def fmt(v: float) -> str:
    return f"{v:.3e}"


def write(out: Path, command: str) -> None:
    runs = _read(out / "runs.csv") if (out / "runs.csv").exists() else []
    lines = [
        "# Mitsuba's own gradient on every task",
        "",
        f"Written by `target/venv/bin/python {command}` (docs/mitsuba.md, "
        "\"Mitsuba's own gradient\"). Each task's scene is its export (`pathtracer export`); "
        "Mitsuba 3 (`llvm_ad_rgb`) differentiates the image MSE against the target rendered with "
        "the run's seed, and the chain rule through the exporter's map gives dL/dtheta "
        "(studies/mitsuba/_chain.py; tested against finite differences of Mitsuba's loss by "
        "python/tests/test_mitsuba_gradient.py). Adam (0.9, 0.999, 1e-8) at the task's learning "
        "rate (supplemental Table 1) in the task's parameters, from the task's start, clamped to "
        "the task's box after each step as our runs do; every render (reference included) uses the "
        "run's seed, as in our renderer's runs.",
        "",
        "Integrator: `prb_projective` (with `guiding` `none`, see docs/mitsuba.md) where a "
        "parameter moves geometry (CUP's rotation, SHADOW's sphere, OCCLUSION's depth, GI's light "
        "and box, SORT's cubes, CAUSTIC's emitter; GI's wall reflectance rides along), `prb` for "
        "TEXTURE's texels (they move nothing). Depth and spp are the task's.",
        "",
        "Starts: every task's start is fixed (SORT's too: its cubes' start positions come from a "
        "fixed hash in examples/pathtracer/src/tasks/sort.rs, not from the run's seed); the seed "
        "is the renderer's (Mitsuba's `seed`, for the reference and every iteration), so seeds "
        "differ in the noise of the renders and of the gradient.",
        "",
        "**Reduced** from the paper's settings to fit the 2 shared cores: the resolution (column "
        "`scale`, times the task's) and the iterations (column `iterations` against the paper's). "
        "Seconds per iteration exclude the first (it compiles Mitsuba's kernels).",
        "",
        "| task | seed | integrator | scale | spp | iterations | paper's | LR | start param MSE | final param MSE | start image MSE | final image MSE | s / iteration | zero-gradient iterations | -grad toward target |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    per_task: dict[str, tuple[list, list, list]] = {}
    for r in runs:
        d = out / f"{r['task']}-seed-{r['seed']}"
        st = history_stats(d / "history.csv")
        tw = toward(st, _target(r["task"], d)) if "theta" in st else None
        per_task.setdefault(r["task"], ([], [], []))
        per_task[r["task"]][0].append(r)
        per_task[r["task"]][1].append(st)
        per_task[r["task"]][2].append(tw)
        lines.append(
            f"| {r['task']} | {r['seed']} | {r['integrator']} | {float(r['scale']):g} | {r['spp']} | "
            f"{r['iterations']} | {PAPER_ITERATIONS[r['task']]} | {float(r['lr']):g} | "
            f"{fmt(float(r['start_param_mse']))} | {fmt(float(r['final_param_mse']))} | "
            f"{fmt(float(r['start_image_mse']))} | {fmt(float(r['final_image_mse']))} | "
            f"{float(r['seconds_per_iteration']):.2f} | {st['zero']} of {st['n']} | "
            f"{'-' if tw is None else f'{100 * tw:.0f} %'} |")
    lines += _summary(per_task) + _images(out, per_task) + _missing(per_task, command)
    _page.write(out.parent / (out.name + ".md"), lines, runs=out)


def _target(task: str, run_dir: Path) -> list[float]:
    """The task's target, from the exporter (``run_dir`` is not needed: it is the task's)."""
    import tempfile

    from studies.mitsuba import _export as mx

    with tempfile.TemporaryDirectory() as tmp:
        return [float(v) for v in mx.run_export(task, tmp, "target")["theta"]]


def _summary(per_task: dict[str, tuple[list, list, list]]) -> list[str]:
    lines = [
        "",
        "## Per task: where the gradient works and where it fails",
        "",
        "Verdict rules (applied to the runs above): a run *works* when its parameter MSE falls at "
        "least 10x from the start. The runs that do not are then classed, in this order: *a "
        "plateau* when the gradient is exactly zero in most of their iterations; else, for tasks "
        "of up to 6 parameters, by the share of iterations (with a nonzero gradient) whose descent "
        "direction -grad points toward the target (the first table's last column, averaged over "
        "those runs): under 40 % *misleading*, 40-60 % *a plateau under noise* (a coin's toss: the "
        "gradient carries no information about where the target is); else *misleading* when "
        "their parameter MSE grows; else *too slow*.",
        "",
        "How we compare with the paper's Mitsuba column: our parameters are the tasks' normalised "
        "ones ([0, 1] per parameter; SHADOW's are world units, like the paper's). The paper's "
        "Mitsuba parameter MSEs (OCCLUSION 52.3, CAUSTIC 8.50, SORT 6.64) exceed anything possible "
        "in [0, 1], so they are in the paper's scene units and the numbers are not comparable "
        "except SHADOW's; we compare the outcome: whether Mitsuba's gradient reaches the paper's "
        "plateau-free parameter MSE, improves on the start, or fails, and the ratio final / start.",
        "",
        "| task | paper: plateau-free param MSE | paper: Mitsuba param MSE | here: final param MSE per seed | here: final / start | verdict |",
        "|---|---|---|---|---|---|",
    ]
    for task in TASKS:
        if task not in per_task:
            continue
        runs, stats, towards = per_task[task]
        ratios = ", ".join(f"{float(r['final_param_mse']) / float(r['start_param_mse']):.3g}" for r in runs)
        p = PAPER.get(task)
        finals = ", ".join(fmt(float(r["final_param_mse"])) for r in runs)
        lines.append(f"| {task} | {fmt(p[1]) if p else '-'} | {p[3] if p else '-'} | {finals} | {ratios} | "
                     f"{verdict(runs, stats, towards)} |")
    return lines


def _images(out: Path, per_task: dict[str, tuple[list, list, list]]) -> list[str]:
    lines = ["", "## Images (seed 0: target, start, Mitsuba's gradient's final)", ""]
    for task in TASKS:
        d = out / f"{task}-seed-0"
        if task in per_task and (d / "final.png").exists():
            rel = f"{out.name}/{task}-seed-0"
            lines.append(f"{task}: ![target]({rel}/reference.png) ![start]({rel}/start.png) "
                         f"![final]({rel}/final.png)")
            lines.append("")
    return lines


def _missing(per_task: dict[str, tuple[list, list, list]], command: str) -> list[str]:
    short = [f"{t} seed {r['seed']} ({r['iterations']} of {max(int(q['iterations']) for q in runs)})"
             for t, (runs, _, _) in per_task.items() for r in runs
             if int(r["iterations"]) < max(int(q["iterations"]) for q in runs)]
    lines = ["", f"Stopped early by `--stop-at` (iterations done): {', '.join(short)}."] if short else []
    done = {(t, int(r["seed"])) for t, (runs, _, _) in per_task.items() for r in runs}
    missing = [f"{t} seed {s}" for t in TASKS for s in (0, 1, 2) if (t, s) not in done]
    if not missing:
        return lines
    return lines + ["", f"Not run (out of time on the shared machine): {', '.join(missing)}. The same command "
            f"runs only what is missing: `target/venv/bin/python {command}`."]
