"""The tasks' default method (``polished``) on their Mitsuba twins, through the Python package.

For each task and seed: the task's Mitsuba twin (_twin.py, moved by the exporter),
the target rendered with the run's seed, and ``plateau_free.minimize(fun, start,
method="polished", sigma0, lr, samples, budget=samples x iterations, seed, bounds)`` with the
task's supplemental Table 1 row as the export gives it (``defaults``), every render with the
run's seed (the loss is a deterministic function of theta, zero at the target, as in our
renderer's runs). Each task runs at its setting in ``SETTINGS`` (resolution and budget
multipliers that fit the 2 shared cores of the machine the page was made on; the page says
so), or at ``--scale`` and ``--budget-scale`` when given.

    target/venv/bin/python -m studies mitsuba-twins --tasks cup,occlusion \\
        --seeds 0,1,2 --out docs/results/mitsuba-twins

writes ``OUT/<task>-seed-<k>.json`` and its final and target images ``OUT/<task>-seed-<k>-final.png``,
``-target.png`` (kept: a second call runs only what is missing; ``--images`` renders the
images of stored runs that have none, from their final theta) and the page ``OUT.md`` over
every stored run.
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

from studies import _page
from studies.mitsuba._files import write_png


TASKS = ("cup", "shadow", "occlusion", "gi", "sort", "caustic", "texture")
# SHADOW has its own study at full resolution (optimize.py, docs/results/mitsuba-polished.md).
DEFAULT_TASKS = tuple(t for t in TASKS if t != "shadow")
# (resolution multiplier, budget multiplier) per task: half resolution at the paper's budget
# where that fits in 30 minutes a run; GI (0.7 s a render at half resolution with 5 jobs on
# the 2 cores: 2,000 renders did not fit) at a quarter; SORT and TEXTURE (64,000 and 128,000 renders at the
# paper's budget, 0.2-0.4 s a render here with 5 jobs on 2 cores) at full resolution and a
# small part of it (about 320 renders, a few minutes a run).
SETTINGS: dict[str, tuple[float, float]] = {
    "cup": (0.5, 1.0), "shadow": (0.5, 1.0), "occlusion": (0.5, 1.0), "gi": (0.25, 1.0),
    "caustic": (0.5, 1.0), "sort": (1.0, 0.005), "texture": (1.0, 0.0025),
}


def target_theta(task: str, scale: float | None) -> np.ndarray:
    import tempfile

    from studies.mitsuba import _export as mx

    with tempfile.TemporaryDirectory() as tmp:
        return np.array(mx.theta_of(mx.run_export(task, tmp, "target", scale=scale)), dtype=np.float64)


METHODS = ("polished", "adaptive", "plateau")


def method_options(method: str, d: dict[str, Any], budget: int) -> dict[str, Any]:
    """``minimize``'s options for ``method`` from the task's Table 1 row ``d``: polished and the
    paper's loop take its sigma0, learning rate and samples; the adaptive search its sigma0."""
    if method not in METHODS:
        raise ValueError(f"method: {method!r}; allowed: {', '.join(METHODS)}")
    options: dict[str, Any] = {"method": method, "sigma0": float(d["sigma0"]), "budget": budget}
    if method != "adaptive":
        options.update(lr=float(d["lr"]), samples=int(d["samples"]))
    return options


def one_run(mi, task: str, seed: int, scale: float, budget_scale: float, out: Path,
            method: str = "polished") -> dict[str, Any]:
    import plateau_free

    from studies.mitsuba import _twin as mt

    twin = mt.Twin(mi, task, scale=scale)
    d = twin.desc["defaults"]
    start = np.array(twin.theta, dtype=np.float64)
    target = target_theta(task, scale)
    reference = twin.render(target, seed)
    budget = max(2 * int(d["samples"]), int(round(d["samples"] * d["iterations"] * budget_scale)))
    box = mt.task_box(d, len(start))
    bounds = None if box is None else list(zip(*box))
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

    result = plateau_free.minimize(fun, start, **method_options(method, d, budget), seed=seed,
                                   batched=True, bounds=bounds)
    seconds = time.perf_counter() - t0
    x = np.asarray(result.x, dtype=np.float64)
    final = twin.render(x, seed)
    write_png(mi, final, out / f"{task}-seed-{seed}-final.png")
    write_png(mi, reference, out / f"{task}-seed-{seed}-target.png")
    return {
        "task": task, "method": method, "seed": seed, "scale": scale, "spp": twin.spp,
        "width": int(twin.desc["film"]["width"]), "height": int(twin.desc["film"]["height"]),
        "budget": budget, "paper_budget": int(d["samples"] * d["iterations"]), "nfev": int(result.nfev),
        "start_param_mse": mt.param_mse(start, target, d),
        "param_mse": mt.param_mse(x, target, d), "image_mse": float(result.fun),
        "start_image_mse": float(np.mean((twin.render(start, seed) - reference) ** 2)),
        "seconds": seconds, "seconds_per_render": seconds / max(renders, 1),
        "final_theta": x.tolist() if len(x) <= 1000 else None,
        "optimiser": f"plateau-free {plateau_free.__version__}",
        "command": command_line(),
    }


def command_line() -> str:
    return "target/venv/bin/python -m studies mitsuba-twins " + " ".join(sys.argv[1:])


def images_of_stored(mi, row: dict[str, Any], out: Path) -> bool:
    """Renders a stored run's final and target images (if missing) from its final theta."""
    from studies.mitsuba import _twin as mt

    task, seed = row["task"], int(row["seed"])
    final_png = out / f"{task}-seed-{seed}-final.png"
    if final_png.exists() or row.get("final_theta") is None:
        return False
    twin = mt.Twin(mi, task, scale=float(row["scale"]))
    reference = twin.render(target_theta(task, float(row["scale"])), seed)
    final = twin.render(row["final_theta"], seed)
    write_png(mi, final, final_png)
    write_png(mi, reference, out / f"{task}-seed-{seed}-target.png")
    return True


def complete_command(task: str, seeds: list[int], out: Path) -> str:
    return ("nice -n 5 target/venv/bin/python -m studies mitsuba-twins "
            f"--tasks {task} --seeds {','.join(map(str, seeds))} --out {out}")


def stored_runs(out: Path) -> list[dict[str, Any]]:
    rows = [json.loads(p.read_text()) for p in out.glob("*-seed-*.json")]
    return sorted(rows, key=lambda r: (TASKS.index(r["task"]), int(r["seed"])))


def page(rows: list[dict[str, Any]], out: Path, seeds: list[int], tasks: tuple[str, ...] = DEFAULT_TASKS) -> str:
    commands = sorted({r["command"] for r in rows if r.get("command")})
    lines = [
        "# The tasks' default method on their Mitsuba twins",
        "",
        "Written by `target/venv/bin/python -m studies mitsuba-twins --page-only "
        f"--out {out}` from the stored runs in `{out}/` (docs/mitsuba.md, \"Every task on Mitsuba\").",
        "Each task's scene is its export (`pathtracer export`), moved at every render by the",
        "exporter (studies/mitsuba/_twin.py); the optimiser is the Python package's",
        "`minimize(method=\"polished\")` with the task's supplemental Table 1 row, from the task's",
        "start, every render with the run's seed.",
        "",
        "**Reduced** from the paper's settings, to fit the 2 shared cores of the machine: every run "
        "at the resolution multiplier `scale` (the `size` column) and the budget in the `budget` "
        "column against `paper budget` (CUP, OCCLUSION and CAUSTIC at half resolution and the "
        "paper's budget, GI at a quarter resolution and the paper's budget; SORT and TEXTURE at full "
        "resolution and a small part of it). SHADOW's "
        "polished runs on Mitsuba are its own study at full resolution and the paper's budget: "
        "[mitsuba-polished.md](mitsuba-polished.md).",
        "",
        "| task | method | seed | scale | size | spp | budget | paper budget | start param MSE | final param MSE | "
        "start image MSE | final image MSE | s / render |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['task']} | {r.get('method', 'polished')} | {r['seed']} | {r['scale']:g} | {r['width']}x{r['height']} | {r['spp']} "
            f"| {r['budget']} | {r['paper_budget']} | {r['start_param_mse']:.3e} | {r['param_mse']:.3e} "
            f"| {r['start_image_mse']:.3e} | {r['image_mse']:.3e} | {r['seconds_per_render']:.3f} |")
    done = {(r["task"], int(r["seed"])) for r in rows}
    missing = {t: [s for s in seeds if (t, s) not in done] for t in tasks}
    lines += ["", "Not run (the command that completes it):" if any(missing.values()) else "Not run: none."]
    for t, m in missing.items():
        if m:
            lines.append(f"- {t} seed{'s' if len(m) > 1 else ''} {', '.join(map(str, m))}: "
                         f"`{complete_command(t, m, out)}`")
    lines += ["", "Every run is made again (deterministic given its seed) by deleting its JSON and running "
              f"`{complete_command('TASK', [0], out).replace('--seeds 0', '--seeds SEED')}`, which uses the "
              "task's setting in `SETTINGS`."]
    if commands:
        lines += ["The runs that stored their command line were made by:", ""] + [f"- `{c}`" for c in commands]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True)
    p.add_argument("--tasks", default=",".join(DEFAULT_TASKS),
                   help="comma-separated (default: all but shadow, which has its own study)")
    p.add_argument("--seeds", default="0,1,2")
    p.add_argument("--scale", type=float, default=None, help="resolution multiplier [default: the task's in SETTINGS]")
    p.add_argument("--budget-scale", type=float, default=None, help="budget multiplier [default: the task's in SETTINGS]")
    p.add_argument("--stop-at", default=None, help="HH:MM (UTC): start no run after this time")
    p.add_argument("--page-only", action="store_true")
    p.add_argument("--images", action="store_true", help="render the images of stored runs that have none")
    args = p.parse_args(argv)
    tasks = [t for t in args.tasks.split(",") if t]
    if not tasks or any(t not in TASKS for t in tasks):
        p.error(f"--tasks: {args.tasks!r}; allowed: {', '.join(TASKS)}")
    seeds = [int(s) for s in args.seeds.split(",") if s]
    if args.budget_scale is not None and not 0 < args.budget_scale <= 1:
        p.error(f"--budget-scale: {args.budget_scale}; allowed: a number > 0 and <= 1")
    if args.scale is not None and not args.scale > 0:
        p.error(f"--scale: {args.scale}; allowed: a number > 0")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if not args.page_only:
        from studies.mitsuba._scene import load_mitsuba

        mi = load_mitsuba()
        for task in tasks:
            scale = args.scale if args.scale is not None else SETTINGS[task][0]
            budget_scale = args.budget_scale if args.budget_scale is not None else SETTINGS[task][1]
            for seed in seeds:
                path = out / f"{task}-seed-{seed}.json"
                late = args.stop_at and time.strftime("%H:%M", time.gmtime()) >= args.stop_at
                if path.exists():
                    if args.images and images_of_stored(mi, json.loads(path.read_text()), out):
                        print(f"{task} seed {seed}: images", flush=True)
                    continue
                if args.images or late:
                    continue
                row = one_run(mi, task, seed, scale, budget_scale, out)
                path.write_text(json.dumps(row, indent=1) + "\n")
                print(f"{task} seed {seed}: param MSE {row['start_param_mse']:.3e} -> {row['param_mse']:.3e} "
                      f"({row['seconds']:.0f} s)", flush=True)
    page_path = out.parent / f"{out.name}.md"
    _page.write(page_path, page(stored_runs(out), out, [0, 1, 2]), runs=out)
    print(page_path)


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    main()
