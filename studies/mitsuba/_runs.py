"""One seed of the Mitsuba SHADOW example (optimize.py): plateau-free's paper loop, its
adaptive search, or the loop polished by the adaptive search, on Mitsuba renders, the run's files (images, history.csv, summary.json,
convergence.png) and its settings."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

try:
    import plateau_free
except ImportError:
    sys.exit("the Python package plateau-free is not installed: `pip install plateau-free` "
             "(or, from a clone of the repository, `pip install ./python`)")

from studies.mitsuba import _scene as ms  # imports no mitsuba itself
from studies.mitsuba._ad import run_ad
from studies.mitsuba._files import (
    PAPER_MITSUBA_PARAM_MSE,
    PAPER_PARAM_MSE,
    plot_convergence,
    read_csv,
    write_csv,
    write_png,
)

# The summaries' "optimiser": the package and its version.
OPTIMISER = f"plateau-free {plateau_free.__version__}"


# --------------------------------------------------------------------------------------
# The images every run writes.

def start_images(mi, args, seed: int, out: Path):
    """The run's scene, its target image (the reference) and its start image, both written
    as PNGs into ``out``."""
    scene = ms.ShadowScene(mi, spp=args.spp, scale=args.scale)
    reference = scene.render(ms.TARGET, seed)
    initial = scene.render(ms.START, seed)
    write_png(mi, reference, out / "target.png")
    write_png(mi, initial, out / "initial.png")
    return scene, reference, initial


def finish_images(mi, scene, final_theta, seed: int, rows: list[dict], out: Path):
    """The final image (written as final.png, with the run's history.csv) and the image MSE
    of the final parameters rendered with another seed, against the target with that seed."""
    final = scene.render(final_theta, seed)
    write_png(mi, final, out / "final.png")
    other = seed + 0x5EED
    image_mse_other_seed = ms.image_mse(scene.render(final_theta, other), scene.render(ms.TARGET, other))
    write_csv(out / "history.csv", rows)
    return final, image_mse_other_seed


# --------------------------------------------------------------------------------------
# plateau-free's paper loop on Mitsuba.

def run_plateau(mi, args, seed: int, out: Path) -> dict:
    import numpy as np

    scene, reference, initial = start_images(mi, args, seed, out)

    calls: list[tuple[np.ndarray, float, float]] = []  # (theta, loss, time)
    t0 = [0.0]

    def record(x, value):
        calls.append((np.array(x, dtype=np.float64), value, time.perf_counter() - t0[0]))
        return value

    if args.crn == "pair":
        def fun(x, s):
            return record(x, ms.image_mse(scene.render(x, s), reference))
    else:
        def fun(x):
            return record(x, ms.image_mse(scene.render(x, seed), reference))

    # The iterates, from plateau-free's scipy-style callback (x after the step, sigma, the
    # iteration's mean value); the time is the optimisation's (renders, estimator, Adam).
    steps: list[dict] = []

    def callback(intermediate_result):
        r = intermediate_result
        steps.append({"x": np.array(r.x, dtype=np.float64), "sigma": float(r.sigma),
                      "seconds": time.perf_counter() - t0[0]})
        k = len(steps)
        if args.progress and (k % args.progress == 0 or k == args.iterations):
            print(f"  seed {seed} iteration {k}: param MSE {ms.param_mse(steps[-1]['x']):.3e}, "
                  f"sigma {steps[-1]['sigma']:.3f}, {steps[-1]['seconds'] / k:.2f} s/iteration",
                  file=sys.stderr, flush=True)

    t0[0] = time.perf_counter()
    result = plateau_free.minimize(fun, np.array(ms.START, dtype=np.float64), method="plateau",
                                   sigma0=args.sigma0, iterations=args.iterations, lr=args.lr,
                                   samples=args.samples, sampling="radial", seed=seed,
                                   seeded=(args.crn == "pair"), callback=callback)
    nit = int(result.nit)
    # Optimisation time: up to the last iteration's step (plateau_free.minimize evaluates fun once
    # more at the end for result.fun; that render is not part of an iteration).
    seconds_total = steps[-1]["seconds"] if steps else time.perf_counter() - t0[0]
    final_theta = np.asarray(result.x, dtype=np.float64)

    # history.csv: row k is iteration k's renders (at the theta before its step: the mean of
    # its antithetic points), its sigma and loss (their mean image MSE).
    n = args.samples
    rows = []
    for k in range(min(nit, len(calls) // n)):
        group = calls[k * n:(k + 1) * n]
        theta = np.mean([g[0] for g in group], axis=0)
        rows.append({
            "iteration": k,
            "sigma": steps[k]["sigma"] if k < len(steps) else plateau_free.Annealer.paper(args.sigma0, args.iterations).sigma(k),
            "loss": float(np.mean([g[1] for g in group])),
            "param_mse": ms.param_mse(theta),
            "image_mse": None,
            "seconds": steps[k]["seconds"] if k < len(steps) else group[-1][2],
            "theta0": float(theta[0]),
            "theta1": float(theta[1]),
        })
    # Image MSE of the current theta every eval_every iterations (rendered after the run:
    # not part of the optimisation's time).
    for r in rows:
        if r["iteration"] % args.eval_every == 0:
            r["image_mse"] = ms.image_mse(scene.render((r["theta0"], r["theta1"]), seed), reference)
    final, image_mse_other_seed = finish_images(mi, scene, final_theta, seed, rows, out)
    return {
        "optimiser": OPTIMISER,
        "nit": nit,
        "nfev": int(result.nfev),
        "initial_param_mse": ms.param_mse(ms.START),
        "initial_image_mse": ms.image_mse(initial, reference),
        "param_mse": ms.param_mse(final_theta),
        "image_mse": ms.image_mse(final, reference),
        "image_mse_other_seed": image_mse_other_seed,
        "seconds_per_iteration": seconds_total / nit,
        "seconds_per_evaluation": seconds_total / (nit * args.samples),
        "seconds_total": seconds_total,
        "final_theta": [float(v) for v in final_theta],
        "reached_paper_param_mse": ms.param_mse(final_theta) <= PAPER_PARAM_MSE,
        "width": int(reference.shape[1]),
        "height": int(reference.shape[0]),
    }


# --------------------------------------------------------------------------------------
# plateau-free's adaptive search on Mitsuba (--method adaptive), or the paper's loop polished by it
# (--method polished).

def spread(points) -> float:
    """RMS distance per coordinate of a batch's points around their mean (the pathtracer's
    adaptive rows report the same)."""
    import numpy as np

    p = np.asarray(points, dtype=np.float64)
    return float(np.sqrt(np.mean((p - p.mean(axis=0)) ** 2))) if len(p) else float("nan")


def run_adaptive(mi, args, seed: int, out: Path) -> dict:
    """``plateau_free.minimize(method="adaptive")`` with the paper's budget (N x iterations renders),
    the task's sigma0 and the run's seed, no bounds (SHADOW's parameters are unbounded): as
    ``pathtracer optimize shadow --method adaptive`` (examples/pathtracer/src/run/adaptive.rs).
    With ``args.method == "polished"``: ``plateau_free.minimize(method="polished")`` with the same
    budget, seed and the paper loop's sigma0, lr and samples (Table 1), ``polish=args.polish``,
    as ``pathtracer optimize shadow --method polished``: the paper's loop on the first
    ``1 - polish`` of the renders, then the adaptive search from its best point.

    The objective is the plateau runs': the image MSE against the target, every render with the
    run's seed (--crn fixed), or with the seed plateau-free gives the batch (--crn pair: one seed for
    all points of a generation, a new one per generation; one per antithetic pair in the
    paper's loop). plateau-free hands each batch's points over at once (batched=True): one row of
    history.csv per batch (a generation, or a gradient estimate of the paper's loop).
    """
    import numpy as np

    scene, reference, initial = start_images(mi, args, seed, out)
    budget = args.samples * args.iterations

    # Per generation: its points, values and the optimisation time at its end (renders and the
    # search's own work; the image-error renders below come after the run).
    batches: list[tuple[np.ndarray, np.ndarray, float]] = []
    t0 = time.perf_counter()

    def evaluate(X, seeds):
        X = np.asarray(X, dtype=np.float64)
        values = np.array([ms.image_mse(scene.render(x, int(s)), reference) for x, s in zip(X, seeds)])
        batches.append((X.copy(), values, time.perf_counter() - t0))
        if args.progress:
            done = sum(len(b[1]) for b in batches)
            if done // (args.progress * args.samples) != (done - len(X)) // (args.progress * args.samples) or done >= budget:
                best = min(float(b[1].min()) for b in batches)
                print(f"  seed {seed} renders {done}/{budget}: best image MSE {best:.3e}, spread {spread(X):.3f}, "
                      f"{batches[-1][2] / done:.2f} s/render", file=sys.stderr, flush=True)
        return values

    if args.crn == "pair":
        def fun(X, seeds):
            return evaluate(X, seeds)
    else:
        def fun(X):
            return evaluate(X, [seed] * len(X))

    if args.method == "polished":
        options = {"method": "polished", "sigma0": args.sigma0, "lr": args.lr, "samples": args.samples,
                   "polish": args.polish}
    else:
        options = {"method": "adaptive", "sigma0": args.sigma0}
    t0 = time.perf_counter()
    result = plateau_free.minimize(fun, np.array(ms.START, dtype=np.float64), budget=budget, seed=seed,
                                   batched=True, seeded=(args.crn == "pair"), **options)
    seconds_total = batches[-1][2] if batches else time.perf_counter() - t0
    final_theta = np.asarray(result.x, dtype=np.float64)

    # history.csv: row k is batch k (row 0 the start, rendered first and alone, phase "start";
    # then a generation; polished: first the paper loop's gradient estimates and its final
    # render, phase "loop", then the generations, phase "polish"): its
    # size, the renders so far, the spread of its points, its mean image MSE (loss); the best
    # point so far (what the run returns), its loss, parameter MSE and (every eval_every x N
    # renders, and last) its image MSE rendered with the run's seed.
    polished = args.method == "polished"
    phase, loop_renders = "loop", 0
    rows = []
    best_value, best_x, nfev = math.inf, np.array(ms.START, dtype=np.float64), 0
    stride = max(args.eval_every * args.samples, 1)
    for k, (X, values, seconds) in enumerate(batches):
        before = nfev
        nfev += len(values)
        for x, v in zip(X, values):
            if math.isfinite(v) and v < best_value:
                best_value, best_x = float(v), x.copy()
        start = k == 0 and len(values) == 1 and np.array_equal(X[0], ms.START)
        row = {"phase": "start" if start else phase} if polished else {}
        if polished and phase == "loop" and not start:
            loop_renders = nfev
            if len(values) == 1:  # the loop's final render: the polish starts after it
                phase = "polish"
        rows.append(row | {
            "iteration": k,
            "population": len(values),
            "renders": nfev,
            "sigma": spread(X),
            "loss": float(np.mean(values)),
            "best_loss": best_value,
            "param_mse": ms.param_mse(best_x),
            "image_mse": None,
            "seconds": seconds,
            "theta0": float(best_x[0]),
            "theta1": float(best_x[1]),
            "_measure": before == 0 or before // stride != nfev // stride or k == len(batches) - 1,
        })
    for r in rows:
        if r.pop("_measure"):
            r["image_mse"] = ms.image_mse(scene.render((r["theta0"], r["theta1"]), seed), reference)
    final, image_mse_other_seed = finish_images(mi, scene, final_theta, seed, rows, out)
    nit = int(result.nit)
    nfev = int(result.nfev)
    return ({"polish": args.polish, "loop_renders": loop_renders} if polished else {}) | {
        "optimiser": OPTIMISER,
        "budget": budget,
        "nit": nit,
        "nfev": nfev,
        "restarts": None if result.get("restarts") is None else int(result.restarts),
        "message": str(result.message),
        "final_sigma": None if result.get("sigma") is None else float(result.sigma),
        "initial_param_mse": ms.param_mse(ms.START),
        "initial_image_mse": ms.image_mse(initial, reference),
        "param_mse": ms.param_mse(final_theta),
        "image_mse": ms.image_mse(final, reference),
        "best_loss": float(result.fun),
        "image_mse_other_seed": image_mse_other_seed,
        "seconds_per_iteration": seconds_total / max(nit, 1),
        "seconds_per_evaluation": seconds_total / max(nfev, 1),
        "seconds_total": seconds_total,
        "final_theta": [float(v) for v in final_theta],
        "reached_paper_param_mse": ms.param_mse(final_theta) <= PAPER_PARAM_MSE,
        "width": int(reference.shape[1]),
        "height": int(reference.shape[0]),
    }


# --------------------------------------------------------------------------------------
# One seed: its settings, the run, its summary and plot.

def settings(args, seed: int) -> dict:
    if args.method == "polished":
        # The paper loop's settings (its sampler, annealer, learning rate), and the share of
        # the renders that the adaptive search gets after it.
        return settings_plateau(args, seed) | {"polish": args.polish}
    return {
        "task": "shadow",
        "backbone": "mitsuba",
        "method": args.method,
        "variant": args.variant,
        "sampling": "radial",
        "antithetic": True,
        "anneal": "paper",
        "crn": args.crn,
        "seed": seed,
        "iterations": args.iterations,
        "samples": args.samples,
        "sigma0": args.sigma0,
        "lr": args.lr,
        "spp": args.spp,
        "scale": args.scale,
        "max_depth": ms.MAX_DEPTH,
        "start_theta": list(ms.START),
        "target_theta": list(ms.TARGET),
        "paper_param_mse": PAPER_PARAM_MSE,
        "paper_mitsuba_param_mse": PAPER_MITSUBA_PARAM_MSE,
    } if args.method == "plateau" else {
        # The adaptive search has no sampler, annealer or learning rate: its budget is the
        # paper loop's renders (samples x iterations), its starting spread sigma0.
        k: v for k, v in settings_plateau(args, seed).items() if k not in ("sampling", "antithetic", "anneal", "lr")
    }


def settings_plateau(args, seed: int) -> dict:
    return settings(argparse.Namespace(**{**vars(args), "method": "plateau"}), seed) | {"method": args.method}


def run_one(mi, args, seed: int, out: Path, ad: dict | None) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    summary = settings(args, seed)
    summary["mitsuba_version"] = mi.__version__
    summary["load_average_at_start"] = os.getloadavg()[0]
    summary["cpus"] = os.cpu_count()
    if args.method in ("adaptive", "polished"):
        what = ("plateau-free's adaptive search" if args.method == "adaptive"
                else f"plateau-free's paper loop polished by its adaptive search (polish {args.polish})")
        print(f"seed {seed}: {what} on Mitsuba, {args.samples * args.iterations} renders -> {out}",
              file=sys.stderr, flush=True)
        summary.update(run_adaptive(mi, args, seed, out))
        unit = "generations" if args.method == "adaptive" else "iterations (the loop's, then generations)"
        print(f"seed {seed}: parameter MSE {summary['param_mse']:.3e}, {summary['nit']} {unit}, "
              f"{summary['seconds_per_evaluation']:.2f} s/render", file=sys.stderr, flush=True)
        (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        replot_adaptive(mi, args, out, summary)
        return summary
    print(f"seed {seed}: plateau-free on Mitsuba, {args.iterations} iterations -> {out}", file=sys.stderr, flush=True)
    summary.update(run_plateau(mi, args, seed, out))
    print(f"seed {seed}: parameter MSE {summary['param_mse']:.3e}, "
          f"{summary['seconds_per_iteration']:.2f} s/iteration", file=sys.stderr, flush=True)
    if ad is None and args.ad_iterations > 0:  # a single run: its own AD
        print(f"Mitsuba AD ({args.ad_integrator}), at most {args.ad_iterations} iterations", file=sys.stderr, flush=True)
        ad = run_ad(mi, args, seed, out)
        ad["mitsuba_ad_dir"] = "."
    if ad:
        summary.update(ad)
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    replot(mi, args, out, summary)
    return summary


def replot_adaptive(mi, args, out: Path, summary: dict) -> None:
    """The convergence plot of an adaptive or polished run (``summary["method"]``)."""
    if summary.get("method") == "polished":
        label = "polished (Mitsuba)"
        what = (f"plateau-free's paper loop (N={summary['samples']}, LR {summary['lr']}), then its adaptive "
                f"search on the last {summary['polish']:g} of the renders")
    else:
        label, what = "adaptive (Mitsuba)", "plateau-free's adaptive search"
    plot_convergence(out / "convergence.png", [(label, read_csv(out / "history.csv"), {})],
                     f"SHADOW on Mitsuba {mi.__version__}, seed {summary['seed']}: {what} "
                     f"({summary['nfev']} renders, sigma0={summary['sigma0']}, {summary['spp']} spp); best point so far",
                     x="renders")


def replot(mi, args, out: Path, summary: dict) -> None:
    series = [("plateau-free (Mitsuba)", read_csv(out / "history.csv"), {})]
    if "mitsuba_ad_integrator" in summary:
        ad_csv = out / summary.get("mitsuba_ad_dir", ".") / "ad_history.csv"
        if ad_csv.exists():
            series.append((f"Mitsuba AD ({summary['mitsuba_ad_integrator']})", read_csv(ad_csv), {"color": "tab:red"}))
    plot_convergence(out / "convergence.png", series,
                     f"SHADOW on Mitsuba {mi.__version__}, seed {summary['seed']}: plateau-free (N={args.samples}, "
                     f"sigma0={args.sigma0}, {args.spp} spp) vs Mitsuba's gradient")


def time_renders(mi, args, k: int) -> dict:
    """Seconds per Mitsuba render of the scene at the run's resolution and spp (after one
    render that compiles the kernels), and the machine's load while measuring."""
    scene = ms.ShadowScene(mi, spp=args.spp, scale=args.scale)
    scene.render(ms.START, 0)
    load0 = os.getloadavg()[0]
    t = time.perf_counter()
    for i in range(k):
        scene.render(ms.START if i % 2 else ms.TARGET, i)
    per = (time.perf_counter() - t) / k
    img = scene.render(ms.START, 0)
    return {"seconds_per_render": per, "renders": k, "width": int(img.shape[1]), "height": int(img.shape[0]),
            "spp": args.spp, "cpus": os.cpu_count(), "load_average": [load0, os.getloadavg()[0]],
            "mitsuba_version": mi.__version__, "variant": args.variant}
