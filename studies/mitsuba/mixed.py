"""SHADOW on Mitsuba 3 with two kinds of gradient in one backward pass: the sphere's position
(seen only through its shadow, a plateau for Mitsuba's gradient) by plateau_free's estimate,
the wall's RGB reflectance by Mitsuba's own AD, through plateau_free.drjit.PlateauFreeOp.

    target/venv/bin/python -m studies mitsuba-mixed --out out/mitsuba-mixed [--seed S]

The scene is studies/mitsuba/_scene.py's (docs/tasks.md's SHADOW) with Mitsuba's ``prb``
integrator (a path tracer that differentiates the reflectance) at depth 6. The target image has
the sphere at the task's target (-1.5, 1.0) and the wall's reflectance at ``--rho-target``
(default 0.45, 0.6, 0.3); the run starts from the task's start (-0.5, 2.5) and the scene's grey
0.7. Each iteration renders once with Mitsuba's AD on (the reflectance), then
``PlateauFreeOp`` ties the image to the position; ``dr.backward`` of the image MSE gives the
reflectance Mitsuba's gradient and the position ours (``--samples`` renders at perturbed
positions); one ``mi.ad.Adam`` steps both. The paper's SHADOW settings by default (N = 2,
sigma0 = 0.5 annealed as the paper's, LR 0.02, 400 iterations), at ``--scale 0.5`` of
256x192 and ``--spp 16`` to fit a few minutes on two cores. Every render uses the run's seed
(common random numbers, as optimize.py's default ``--crn fixed``). Writes
``summary.json`` and ``history.csv`` into ``--out``.

    target/venv/bin/python -m studies mitsuba-mixed --page docs/results/mitsuba-mixed

writes ``docs/results/mitsuba-mixed.md``, a table of the runs in ``seed-<k>/`` under that folder.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from studies.mitsuba import _scene as ms  # imports no mitsuba itself
from studies.mitsuba._files import write_csv
from studies import _page

RHO_START = (0.7, 0.7, 0.7)
PAPER_PARAM_MSE = 1.81e-3


def wall_reflectance(params) -> str:
    """The key of the wall's reflectance among the scene's parameters: the export names shapes
    by their index and kind (SHADOW has one quad, the wall)."""
    (key,) = [k for k in params.keys() if "_quad." in k and k.endswith("reflectance.value")]
    return key


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", type=Path)
    p.add_argument("--page", type=Path, help="write FOLDER.md from FOLDER/seed-*/summary.json and stop")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--iterations", type=int, default=400)
    p.add_argument("--samples", type=int, default=2)
    p.add_argument("--sigma0", type=float, default=0.5)
    p.add_argument("--lr", type=float, default=0.02)
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--scale", type=float, default=0.5)
    p.add_argument("--rho-target", type=lambda s: tuple(float(v) for v in s.split(",")),
                   default=(0.45, 0.6, 0.3))
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> dict:
    args = parse(argv)
    if args.page is not None:
        return write_page(args.page)
    if args.out is None:
        sys.exit("--out is required (or --page)")
    mi = ms.load_mitsuba()
    try:
        import plateau_free
        from plateau_free.drjit import PlateauFreeOp
    except ImportError:
        sys.exit("plateau_free is not installed: pip install plateau-free (or pip install ./python)")
    import drjit as dr

    scene = ms.ShadowScene(mi, spp=args.spp, scale=args.scale,
                           integrator={"type": "prb", "max_depth": ms.MAX_DEPTH})
    params, seed = scene.params, args.seed
    reflectance = wall_reflectance(params)
    params[reflectance] = mi.Color3f(*args.rho_target)
    reference = mi.TensorXf(scene.render(ms.TARGET, seed))

    op = PlateauFreeOp(lambda x, _pair_seed: scene.render(x, seed), restore=scene.set_theta,
                       samples=args.samples, seed=seed)
    annealer = plateau_free.Annealer.paper(args.sigma0, args.iterations)
    opt = mi.ad.Adam(lr=args.lr)
    opt["theta"] = mi.Float(ms.START)
    opt["rho"] = mi.Color3f(*RHO_START)
    rows, started = [], time.perf_counter()
    for it in range(args.iterations):
        theta = np.array(opt["theta"], dtype=np.float64)
        rho = np.array(opt["rho"], dtype=np.float64).ravel()
        scene.set_theta(theta)
        params[reflectance] = opt["rho"]
        params.update()
        image = op(opt["theta"], mi.render(scene.scene, params, seed=seed, spp=args.spp),
                   annealer.sigma(it))
        loss = dr.mean(dr.square(image - reference), axis=None)
        dr.backward(loss)
        rows.append(row(it, annealer.sigma(it), loss, theta, rho, opt, args, started))
        opt.step()
        opt["rho"] = dr.clip(opt["rho"], 0.0, 1.0)
    return finish(mi, args, scene, reference, opt, rows, op, time.perf_counter() - started)


def row(it, sigma, loss, theta, rho, opt, args, started) -> dict:
    import drjit as dr

    g_theta = np.array(dr.grad(opt["theta"]), dtype=np.float64)
    g_rho = np.array(dr.grad(opt["rho"]), dtype=np.float64).ravel()
    return {
        "iteration": it, "sigma": sigma, "loss": float(np.array(loss).ravel()[0]),
        "param_mse": ms.param_mse(theta), "rho_max_error": rho_error(rho, args.rho_target),
        "theta0": theta[0], "theta1": theta[1], "rho_r": rho[0], "rho_g": rho[1], "rho_b": rho[2],
        "grad_theta0": g_theta[0], "grad_theta1": g_theta[1],
        "grad_rho_r": g_rho[0], "grad_rho_g": g_rho[1], "grad_rho_b": g_rho[2],
        "seconds": time.perf_counter() - started,
    }


def rho_error(rho, target) -> float:
    return float(np.max(np.abs(np.asarray(rho, np.float64) - np.asarray(target, np.float64))))


def finish(mi, args, scene, reference, opt, rows, op, seconds) -> dict:
    theta = np.array(opt["theta"], dtype=np.float64)
    rho = np.array(opt["rho"], dtype=np.float64).ravel()
    scene.params[wall_reflectance(scene.params)] = mi.Color3f(*(float(v) for v in rho))
    final = scene.render(theta, args.seed)
    summary = {
        "seed": args.seed, "iterations": args.iterations, "samples": args.samples,
        "sigma0": args.sigma0, "lr": args.lr, "spp": args.spp, "scale": args.scale,
        "final_theta": theta.tolist(), "param_mse": ms.param_mse(theta),
        "paper_param_mse": PAPER_PARAM_MSE, "reached_paper_param_mse": ms.param_mse(theta) <= PAPER_PARAM_MSE,
        "rho_target": list(args.rho_target), "final_rho": rho.tolist(),
        "rho_max_error": rho_error(rho, args.rho_target),
        "image_mse": ms.image_mse(final, np.array(reference)),
        "perturbed_renders": op.renders, "seconds": seconds,
        "seconds_per_iteration": seconds / max(1, len(rows)),
    }
    args.out.mkdir(parents=True, exist_ok=True)
    write_csv(args.out / "history.csv", rows)
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(json.dumps(summary, indent=2))
    return summary


def write_page(folder: Path) -> dict:
    runs = sorted(folder.glob("seed-*/summary.json"), key=lambda p: int(p.parent.name[5:]))
    summaries = [json.loads(p.read_text()) for p in runs]
    lines = [
        "# SHADOW on Mitsuba 3, position by plateau_free, wall reflectance by Mitsuba's AD",
        "",
        "Written by `target/venv/bin/python -m studies mitsuba-mixed --page "
        f"{folder}` from the runs of `studies/mitsuba/mixed.py --seed K --out {folder}/seed-K`",
        "(see [../mitsuba.md](../mitsuba.md)). One `dr.backward` per iteration gives the sphere's",
        "position plateau_free's gradient (`plateau_free.drjit.PlateauFreeOp`) and the wall's RGB",
        "reflectance Mitsuba's (`prb`); one `mi.ad.Adam` steps both. The paper's parameter MSE",
        f"for SHADOW is {PAPER_PARAM_MSE}.",
        "",
        "| seed | iterations | resolution, spp | param MSE | reached paper's | final reflectance "
        "(target) | max reflectance error | image MSE | s / iteration |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for s in summaries:
        size = f"{round(ms.WIDTH * s['scale'])}x{round(ms.HEIGHT * s['scale'])}, {s['spp']}"
        rho = ", ".join(f"{v:.4f}" for v in s["final_rho"])
        target = ", ".join(f"{v:g}" for v in s["rho_target"])
        lines.append(
            f"| {s['seed']} | {s['iterations']} | {size} | {s['param_mse']:.3g} | "
            f"{'yes' if s['reached_paper_param_mse'] else 'no'} | {rho} ({target}) | "
            f"{s['rho_max_error']:.3g} | {s['image_mse']:.3g} | {s['seconds_per_iteration']:.2f} |"
        )
    reached = sum(s["reached_paper_param_mse"] for s in summaries)
    lines += ["", f"Reached the paper's parameter MSE: {reached} of {len(summaries)} seeds run."]
    page = folder.parent / (folder.name + ".md")
    _page.write(page, lines, runs=folder)
    print(page.read_text())
    return {"seeds": len(summaries), "reached": reached}


if __name__ == "__main__":
    main()
