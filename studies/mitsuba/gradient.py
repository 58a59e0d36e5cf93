"""Mitsuba's own gradient on every task: the paper's "Mitsuba 3" column, measured here.

For each task and seed: the task's scene as ``pathtracer export`` writes it, loaded into
Mitsuba 3 under a differentiable integrator (``prb_projective`` where a parameter moves
geometry, ``prb`` for TEXTURE's texels; ``INTEGRATORS``), the target rendered with the run's
seed, and Adam (beta 0.9 / 0.999, eps 1e-8, bias correction; the task's learning rate, the
export's ``defaults``) on the image MSE from the task's start, with the gradient
dL/dtheta = Mitsuba's dL/d(scene) times the exporter's d(scene)/dtheta (_chain.py),
theta clamped to the task's box after each step as our runs do. Every render uses the run's
seed (common random numbers, as in our renderer's runs).

    target/venv/bin/python -m studies mitsuba-gradient \\
        --tasks cup,shadow,occlusion,gi,sort,caustic,texture --seeds 0,1,2 \\
        --scale 0.25,sort=0.5,texture=1 --iterations 100,gi=60,sort=60,texture=1000 \\
        --out docs/results/mitsuba-gradient

writes ``OUT/runs.csv`` (a run already there is not run again), ``OUT/<task>-seed-<k>/``
(``history.csv``, ``final.png``, ``reference.png``, ``start.png``) and, with ``--page``
(alone it only rewrites the page from the CSV), ``OUT.md``.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent

TASKS = ("cup", "shadow", "occlusion", "gi", "sort", "caustic", "texture")
# prb_projective where a parameter moves geometry (it adds the boundary terms of moving
# silhouettes and shadows); TEXTURE's texels move no geometry, so plain prb.
INTEGRATORS = {t: "prb_projective" for t in TASKS} | {"texture": "prb"}
# prb_projective's guiding of indirect discontinuities: "none" (uniform projective samples).
# Measured on GI's light position (the page, "Choices"): "grid" gave a 40x too small
# derivative against the direct one and a finite difference, "octree" (the default) took
# over 10 minutes for one 32 x 32 render at 64 spp on the shared 2 cores; "none" agrees.
GUIDING = "none"
COLUMNS = ("task", "seed", "integrator", "iterations", "spp", "scale", "lr", "start_param_mse",
           "final_param_mse", "start_image_mse", "final_image_mse", "seconds_per_iteration")


def per_task(text: str, cast) -> dict[str, Any]:
    """``"0.25,sort=0.5"`` -> {task: value} for every task (the bare value is the default)."""
    out: dict[str, Any] = {}
    default = None
    for part in text.split(","):
        if "=" in part:
            task, value = part.split("=", 1)
            if task not in TASKS:
                raise ValueError(f"unknown task {task!r} in {text!r}; tasks: {', '.join(TASKS)}")
            out[task] = cast(value)
        else:
            default = cast(part)
    return {t: out.get(t, default) for t in TASKS}


class Adam:
    """The paper's Adam, with the box projection after each step."""

    def __init__(self, x: np.ndarray, lr: float, box: tuple[np.ndarray, np.ndarray] | None):
        self.x, self.lr, self.box = x.astype(np.float64).copy(), lr, box
        self.m, self.v, self.t = np.zeros_like(self.x), np.zeros_like(self.x), 0

    def step(self, g: np.ndarray) -> None:
        self.t += 1
        self.m = 0.9 * self.m + 0.1 * g
        self.v = 0.999 * self.v + 0.001 * g * g
        mhat, vhat = self.m / (1 - 0.9**self.t), self.v / (1 - 0.999**self.t)
        self.x = self.x - self.lr * mhat / (np.sqrt(vhat) + 1e-8)
        if self.box is not None:
            self.x = np.clip(self.x, *self.box)


def make_twin(mi, task: str, scale: float | None):
    from studies.mitsuba import _chain as mc

    if task == "texture":
        return mc.TextureTwin(mi, INTEGRATORS[task], scale=scale)
    return mc.ChainTwin(mi, task, {"type": INTEGRATORS[task], "guiding": GUIDING}, scale=scale)


def one_run(mi, task: str, seed: int, scale: float | None, cap: int | None, out: Path,
            stop_at: float | None = None) -> dict[str, Any]:
    from studies.mitsuba._files import write_csv, write_png

    from studies.mitsuba import _twin as mt

    twin = make_twin(mi, task, scale)
    d = twin.defaults
    iterations = int(d["iterations"]) if cap is None else min(int(cap), int(d["iterations"]))
    reference = twin.render(twin.target, seed)
    ref = mi.TensorXf(reference.astype(np.float32))
    adam = Adam(twin.start, float(d["lr"]), mt.task_box(d, twin.start.size))
    rows, times = [], []
    for it in range(iterations):
        if stop_at is not None and time.time() >= stop_at and it > 0:
            break  # out of time: the run reports the iterations it did
        t0 = time.perf_counter()
        theta = adam.x.copy()
        loss, grad, image = twin.loss_and_grad(theta, ref, seed)
        if it == 0:
            write_png(mi, image, out / "start.png")
        adam.step(grad.reshape(theta.shape))
        times.append(time.perf_counter() - t0)
        rows.append(history_row(it, loss, mt.param_mse(theta, twin.target, d), theta, grad, times[-1]))
        print(f"  {task} seed {seed} iteration {it}: loss {loss:.4e} param MSE {rows[-1]['param_mse']:.3e} "
              f"|grad| {rows[-1]['grad_norm']:.2e} ({times[-1]:.1f} s)", file=sys.stderr, flush=True)
    final = twin.render(adam.x, seed)
    write_png(mi, reference, out / "reference.png")
    write_png(mi, final, out / "final.png")
    write_csv(out / "history.csv", rows)
    return {
        "task": task, "seed": seed, "integrator": INTEGRATORS[task], "iterations": len(rows),
        "spp": twin.spp, "scale": 1.0 if scale is None else scale, "lr": float(d["lr"]),
        "start_param_mse": mt.param_mse(twin.start, twin.target, d),
        "final_param_mse": mt.param_mse(adam.x, twin.target, d),
        "start_image_mse": rows[0]["loss"], "final_image_mse": float(np.mean((final - reference) ** 2)),
        # The first iteration compiles Mitsuba's kernels: the mean is over the others.
        "seconds_per_iteration": float(np.mean(times[1:] if len(times) > 1 else times)),
    }


def history_row(it: int, loss: float, param_mse: float, theta: np.ndarray, grad: np.ndarray,
                seconds: float) -> dict[str, Any]:
    row: dict[str, Any] = {"iteration": it, "loss": loss, "param_mse": param_mse,
                           "grad_norm": float(np.linalg.norm(grad)), "seconds": seconds}
    if theta.size <= 6:
        row |= {f"theta{i}": float(v) for i, v in enumerate(theta.ravel())}
        row |= {f"grad{i}": float(v) for i, v in enumerate(grad.ravel())}
    return row


def read_runs(path: Path) -> list[dict[str, str]]:
    if not path.exists():
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def append_run(path: Path, row: dict[str, Any]) -> None:
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        if new:
            w.writeheader()
        w.writerow({k: (f"{row[k]:.6e}" if isinstance(row[k], float) else row[k]) for k in COLUMNS})


def stop_time(hhmm: str) -> float:
    """Today's HH:MM UTC as a Unix time."""
    import datetime as dt

    h, m = (int(x) for x in hhmm.split(":"))
    now = dt.datetime.now(dt.timezone.utc)
    return now.replace(hour=h, minute=m, second=0, microsecond=0).timestamp()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--tasks", default=",".join(TASKS))
    p.add_argument("--seeds", default="0,1,2")
    p.add_argument("--scale", default=None, help="resolution scale, e.g. 0.25,sort=0.5,texture=1")
    p.add_argument("--iterations", default=None, help="at most this many (the task's Table 1 count if fewer)")
    p.add_argument("--out", default=str(HERE.parent.parent / "docs" / "results" / "mitsuba-gradient"))
    p.add_argument("--stop-at", default=None, help="HH:MM UTC: no run starts after it, a run stops at it")
    p.add_argument("--page", action="store_true", help="write OUT.md from OUT/runs.csv")
    p.add_argument("--page-only", action="store_true", help="only the page")
    a = p.parse_args(argv)
    tasks = [t for t in a.tasks.split(",") if t]
    for t in tasks:
        if t not in TASKS:
            raise ValueError(f"--tasks: unknown task {t!r}; tasks: {', '.join(TASKS)}")
    seeds = [int(s) for s in a.seeds.split(",") if s]
    scales = per_task(a.scale, float) if a.scale else dict.fromkeys(TASKS)
    caps = per_task(a.iterations, int) if a.iterations else dict.fromkeys(TASKS)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if not a.page_only:
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")
        mi.set_log_level(mi.LogLevel.Error)  # prb_projective's film-border advice, every render
        stop = stop_time(a.stop_at) if a.stop_at else None
        done = {(r["task"], int(r["seed"])) for r in read_runs(out / "runs.csv")}
        for seed in seeds:  # seed-major: every task has a seed early
            for task in tasks:
                if (task, seed) in done or (stop is not None and time.time() >= stop):
                    continue
                run_dir = out / f"{task}-seed-{seed}"
                run_dir.mkdir(exist_ok=True)
                append_run(out / "runs.csv", one_run(mi, task, seed, scales[task], caps[task], run_dir, stop))
    if a.page or a.page_only:
        from studies.mitsuba import _gradient_page as page

        args = [x for x in (argv if argv is not None else sys.argv[1:]) if x not in ("--page", "--page-only")]
        page.write(out, " ".join(["-m studies mitsuba-gradient"] + args + ["--page"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
