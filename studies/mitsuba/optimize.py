#!/usr/bin/env python3
"""Any task on Mitsuba 3: plateau-free through the Python package, and Mitsuba's own gradient.

One command runs any task of docs/tasks.md on its Mitsuba twin (``--task``, default shadow)
with the tasks' default method, ``polished`` (the paper's loop, then the adaptive search):

    python -m studies mitsuba-optimize --task cup --out out/mitsuba-cup [--seed S]
    python -m studies mitsuba-optimize --task gi --seeds 3 --out out/mitsuba-gi

A task other than SHADOW runs on its twin (_twin.py: the task's export, moved by the
exporter) with the task's supplemental Table 1 row from the export, at the resolution and
budget of ``--scale`` and ``--budget-scale`` (default: the task's in twins.SETTINGS),
``--method polished|adaptive|plateau``; it writes ``OUT/<task>-seed-<k>.json`` with the final and
target images and, with ``--seeds``, the page ``OUT.md`` (twins.py). The options
below that name SHADOW are SHADOW's only.

SHADOW (the scene: _scene.py) has the full study: the paper's Table 1
settings (N=2, sigma0=0.5, 32 spp, LR 0.02, 400 iterations), the renderer a black box (image
MSE against the target), optimised

1. by plateau-free (``plateau_free.minimize``), ``--method polished`` by default,
   ``--method plateau`` the paper's loop alone (radial sampler, antithetic pairs, the paper's
   annealer and Adam), ``--method adaptive`` the adaptive search;
2. with ``--method plateau``, by Mitsuba's own gradient: a projective integrator
   (``direct_projective`` by default) differentiated by Dr.Jit, with Adam at the same learning
   rate, for fewer iterations (it costs tens of seconds an iteration on two cores); the summary
   says how many.

One run:

    python -m studies mitsuba-optimize --method plateau --out out/mitsuba-shadow [--seed S]

writes target.png, initial.png, final.png (plateau-free), ad_final.png (Mitsuba AD), history.csv,
ad_history.csv, convergence.png and summary.json into the output folder.

The per-seed study and its results page (docs/results/mitsuba.md):

    python -m studies mitsuba-optimize --method plateau --seeds 5 --out docs/results/mitsuba

runs seeds 0..4 into docs/results/mitsuba/seed-<k>/ (a seed whose summary.json exists is
kept; --force reruns it), Mitsuba's AD once into docs/results/mitsuba/ad/, and writes
docs/results/mitsuba.md beside the folder, with our renderer's SHADOW runs read from
docs/results (--page-only rewrites the page from the runs alone).

plateau-free's general-purpose adaptive search instead of the paper's loop (no Mitsuba AD):

    python -m studies mitsuba-optimize --method adaptive --out out/mitsuba-adaptive [--seed S]
    python -m studies mitsuba-optimize --method adaptive --seeds 5 --out docs/results/mitsuba-adaptive

runs ``plateau_free.minimize(fun, x0, method="adaptive", budget=samples x iterations, sigma0=sigma0,
seed=seed)`` (the paper's budget: 2 x 400 = 800 renders) on the same objective, one row of
history.csv per generation, and with --seeds writes OUT.md comparing each seed with the paper
loop's run (--plateau-runs, default docs/results/mitsuba). --run-seeds 1,4,0 picks the seeds
to run and their order, --stop-at HH:MM starts no new seed after that time.

The paper's loop polished by the adaptive search (no Mitsuba AD):

    python -m studies mitsuba-optimize --method polished --out out/mitsuba-polished [--seed S]
    python -m studies mitsuba-optimize --method polished --seeds 5 --out docs/results/mitsuba-polished

runs ``plateau_free.minimize(fun, x0, method="polished", sigma0=sigma0, lr=lr, samples=samples,
budget=samples x iterations, polish=0.25, seed=seed)`` (the paper's SHADOW settings, Table 1:
sigma0 0.5, LR 0.02, N = 2, 800 renders): the paper's loop on the first 3/4 of the renders,
then the adaptive search from its best point on the rest (--polish sets the share), as
``pathtracer optimize shadow --method polished``. Outputs and options as --method adaptive;
history.csv has a phase column (loop, polish).

Common random numbers, as our task: by default (--crn fixed) every render, the target's
included, uses the run's seed, so the loss is a deterministic function of theta that reaches
zero at the target (our renderer's default and the paper's code). --crn pair gives the
objective plateau-free's seeded=True: both members of an antithetic pair share a fresh seed,
the target keeps the run's seed.

Needs mitsuba: scripts/install-mitsuba installs it (pinned) into target/venv; and the package
itself: `pip install plateau-free` (or `pip install ./python` from a clone of the repository).

The example's modules, beside this file: _scene.py (the scene), _runs.py (one
seed's run), _ad.py (Mitsuba's own gradient), _report.py (the results pages),
_files.py (images, tables, plots), _twin.py and twins.py (the other
tasks); this file is the command line and SHADOW's per-seed study.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from studies import _page
from studies.mitsuba import _scene as ms  # imports no mitsuba itself
from studies.mitsuba._ad import ad_keys, run_ad
from studies.mitsuba._report import write_page, write_page_adaptive
from studies.mitsuba._runs import replot, run_one, settings, time_renders
from studies.mitsuba.twins import TASKS


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--task", choices=TASKS, default="shadow",
                   help="the task (default shadow); another than shadow runs on its Mitsuba twin")
    p.add_argument("--method", choices=["plateau", "adaptive", "polished"], default="polished",
                   help="plateau: the paper's loop (and Mitsuba's AD); adaptive: plateau_free.minimize(method='adaptive') "
                        "with a budget of samples x iterations renders (no AD); polished: "
                        "plateau_free.minimize(method='polished'), the paper's loop then the adaptive search, the same budget")
    p.add_argument("--out", default=None,
                   help="output folder (default out/mitsuba-shadow, or out/mitsuba-shadow-adaptive, -polished)")
    p.add_argument("--seed", type=int, default=0, help="the run's seed (perturbations and renders)")
    p.add_argument("--seeds", type=int, default=0, help="run seeds 0..K-1 into OUT/seed-<k> and write OUT.md")
    p.add_argument("--page-only", action="store_true", help="with --seeds: only rewrite the results page")
    p.add_argument("--page", default=None, help="the results page (default: OUT.md)")
    p.add_argument("--notes", default=None, help="markdown appended to the page (default: NOTES.md beside this file)")
    p.add_argument("--run-pathtracer", action="store_true",
                   help="with --seeds: run our renderer (cargo) for the seeds docs/results lacks")
    p.add_argument("--force", action="store_true", help="with --seeds: rerun seeds that have a summary.json")
    p.add_argument("--run-seeds", default=None,
                   help="with --seeds: the seeds to run, in this order (comma-separated; default 0..K-1); "
                        "the page covers 0..K-1 and names the others not run")
    p.add_argument("--stop-at", default=None,
                   help="with --seeds: start no new seed at or after this time of day (HH:MM, machine clock)")
    p.add_argument("--plateau-runs", default=None,
                   help="with --method adaptive or polished: the paper loop's per-seed runs to compare with "
                        "(default docs/results/mitsuba)")
    p.add_argument("--polish", type=float, default=0.25,
                   help="with --method polished: the share of the renders the adaptive search gets after the "
                        "paper's loop, in [0, 1) (default 0.25, as pathtracer --method polished)")
    p.add_argument("--iterations", type=int, default=400)
    p.add_argument("--samples", type=int, default=2, help="N: renders per gradient")
    p.add_argument("--sigma0", type=float, default=0.5)
    p.add_argument("--lr", type=float, default=0.02)
    p.add_argument("--spp", type=int, default=32)
    p.add_argument("--scale", type=float, default=None,
                   help="resolution factor (SHADOW: default 1, 256x192; another task: default its setting)")
    p.add_argument("--crn", choices=["fixed", "pair"], default="fixed")
    p.add_argument("--eval-every", type=int, default=10, help="render the iterate for image MSE every K iterations")
    p.add_argument("--ad-integrator", default="direct_projective",
                   help="Mitsuba's differentiable integrator (direct_projective, prb_projective, ...)")
    p.add_argument("--ad-iterations", type=int, default=20, help="Mitsuba AD iterations (0: none)")
    p.add_argument("--ad-seconds", type=float, default=0, help="stop Mitsuba AD after this many seconds (0: no limit)")
    p.add_argument("--time-renders", type=int, default=0,
                   help="only time K renders at the run's resolution and spp, into OUT/render_timing.json")
    p.add_argument("--ad-only", action="store_true", help="only Mitsuba's AD run, into OUT/ad (with --seeds: seed 0's renders)")
    p.add_argument("--variant", default="llvm_ad_rgb")
    p.add_argument("--progress", type=int, default=50, help="print progress every K iterations (0: never)")
    p.add_argument("--budget-scale", type=float, default=None,
                   help="a task other than shadow: the share of the paper's budget (default: the task's setting)")
    args = p.parse_args(argv)
    if args.task != "shadow":
        return main_twin(p, args)
    if args.budget_scale is not None:
        p.error("--budget-scale: an option of the tasks other than shadow (SHADOW takes --iterations)")

    if args.scale is None:
        args.scale = 1.0
    if args.method != "polished" and args.polish != 0.25:
        p.error("--polish: an option of --method polished")
    if not 0.0 <= args.polish < 1.0:
        p.error(f"--polish {args.polish}: a share of the renders in [0, 1) expected")
    out = Path(args.out or ("out/mitsuba-shadow" + ("" if args.method == "plateau" else f"-{args.method}")))
    seeds = list(range(args.seeds))
    order = seeds
    if args.run_seeds:
        try:
            order = [int(v) for v in args.run_seeds.split(",") if v.strip()]
        except ValueError:
            p.error(f"--run-seeds: comma-separated seeds expected, got {args.run_seeds!r}")
        if any(v not in seeds for v in order):
            p.error(f"--run-seeds {args.run_seeds}: every seed must lie in 0..{args.seeds - 1} (--seeds {args.seeds})")
    stop_at = None
    if args.stop_at:
        try:
            stop_at = time.strptime(args.stop_at, "%H:%M")
        except ValueError:
            p.error(f"--stop-at: HH:MM expected, got {args.stop_at!r}")
    if args.seeds and args.page_only:
        if args.method in ("adaptive", "polished"):
            write_page_adaptive(args, out, seeds)
        else:
            merge_ad(None, args, out, seeds)
            write_page(args, out, seeds)
        return 0
    for s in seeds:  # a folder holds one method's runs
        f = out / f"seed-{s}" / "summary.json"
        if f.exists() and not args.force and json.loads(f.read_text()).get("method", "plateau") != args.method:
            p.error(f"{f} is a run of method {json.loads(f.read_text()).get('method', 'plateau')!r}, not "
                    f"{args.method!r}: give --method {args.method} its own --out")
    mi = ms.load_mitsuba(args.variant)
    if args.ad_only:
        run_study_ad(mi, args, out, seeds or [args.seed], force=True)
        return 0
    if args.time_renders:
        out.mkdir(parents=True, exist_ok=True)
        t = time_renders(mi, args, args.time_renders)
        (out / "render_timing.json").write_text(json.dumps(t, indent=2) + "\n")
        print(json.dumps(t))
        return 0
    if not args.seeds:
        s = run_one(mi, args, args.seed, out, None)
        print(json.dumps({k: s[k] for k in ("method", "param_mse", "image_mse", "seconds_per_iteration",
                                             "seconds_per_evaluation", "mitsuba_ad_param_mse") if k in s}))
        return 0
    def seeds_to_run():
        """The seeds of ``order`` still to run, with their folders: finished ones are kept, and
        none starts after ``--stop-at``."""
        for s in order:
            d = out / f"seed-{s}"
            if (d / "summary.json").exists() and not args.force:
                print(f"seed {s}: kept {d / 'summary.json'}", file=sys.stderr)
            elif stop_at and time.localtime()[3:5] >= stop_at[3:5]:
                print(f"seed {s}: not started (--stop-at {args.stop_at})", file=sys.stderr)
            else:
                yield s, d

    if args.method in ("adaptive", "polished"):
        for s, d in seeds_to_run():
            run_one(mi, args, s, d, None)
            write_page_adaptive(args, out, seeds)
        write_page_adaptive(args, out, seeds)
        return 0
    ad_file = out / "ad" / "summary.json"
    ad = json.loads(ad_file.read_text()) if ad_file.exists() and not args.force else None
    # plateau-free per seed first (the goal), then Mitsuba's AD once (from the same start, seed 0's
    # renders), whose figures then go into every seed's summary.
    for s, d in seeds_to_run():
        run_one(mi, args, s, d, ad_keys(ad) if ad else {})
        write_page(args, out, seeds)
    if ad is None and args.ad_iterations > 0:
        run_study_ad(mi, args, out, seeds, force=args.force)
    merge_ad(mi, args, out, seeds)
    write_page(args, out, seeds)
    return 0


# --------------------------------------------------------------------------------------
# A task other than SHADOW, on its twin.

SHADOW_ONLY = ("page", "notes", "run_pathtracer", "force", "run_seeds", "plateau_runs", "polish",
               "iterations", "samples", "sigma0", "lr", "spp", "crn", "eval_every", "ad_integrator",
               "ad_iterations", "ad_seconds", "time_renders", "ad_only", "progress")


def main_twin(p, args) -> int:
    """``--task`` other than shadow: the task's Table 1 row on its twin (twins.py)."""
    from studies.mitsuba import twins as tr

    for name in SHADOW_ONLY:
        if getattr(args, name) != p.get_default(name):
            p.error(f"--{name.replace('_', '-')}: an option of --task shadow only (the task's settings come "
                    f"from its export)")
    if args.scale is not None and not args.scale > 0:
        p.error(f"--scale: {args.scale}; allowed: a number > 0")
    if args.budget_scale is not None and not 0 < args.budget_scale <= 1:
        p.error(f"--budget-scale: {args.budget_scale}; allowed: a number > 0 and <= 1")
    scale = args.scale if args.scale is not None else tr.SETTINGS[args.task][0]
    budget_scale = args.budget_scale if args.budget_scale is not None else tr.SETTINGS[args.task][1]
    out = Path(args.out or f"out/mitsuba-{args.task}" + ("" if args.method == "polished" else f"-{args.method}"))
    seeds = list(range(args.seeds)) if args.seeds else [args.seed]
    for s in seeds:  # a folder holds one method's runs
        f = out / f"{args.task}-seed-{s}.json"
        if f.exists() and json.loads(f.read_text()).get("method", "polished") != args.method:
            p.error(f"{f} is a run of another method than {args.method!r}: give it its own --out")
    if not args.page_only:
        mi = ms.load_mitsuba(args.variant)
        out.mkdir(parents=True, exist_ok=True)
        for s in seeds:
            f = out / f"{args.task}-seed-{s}.json"
            late = args.stop_at and time.strftime("%H:%M", time.localtime()) >= args.stop_at
            if (f.exists() and args.seeds) or late:
                continue
            row = tr.one_run(mi, args.task, s, scale, budget_scale, out, args.method)
            f.write_text(json.dumps(row, indent=1) + "\n")
            print(json.dumps({k: row[k] for k in ("task", "method", "seed", "budget", "start_param_mse",
                                                   "param_mse", "image_mse", "seconds_per_render")}), flush=True)
    if args.seeds:
        page = out.parent / f"{out.name}.md"
        _page.write(page, tr.page(tr.stored_runs(out), out, seeds, (args.task,)), runs=out)
        print(page)
    return 0


# --------------------------------------------------------------------------------------
# The study's Mitsuba AD run, once for all seeds.

def run_study_ad(mi, args, out: Path, seeds: list[int], force: bool) -> dict:
    ad_dir = out / "ad"
    ad_file = ad_dir / "summary.json"
    if ad_file.exists() and not force:
        return json.loads(ad_file.read_text())
    ad_dir.mkdir(parents=True, exist_ok=True)
    print(f"Mitsuba AD ({args.ad_integrator}), at most {args.ad_iterations} iterations -> {ad_dir}",
          file=sys.stderr, flush=True)
    ad = run_ad(mi, args, seeds[0], ad_dir)
    ad["initial_param_mse"] = ms.param_mse(ms.START)
    ad_file.write_text(json.dumps({**settings(args, seeds[0]), **ad}, indent=2) + "\n")
    return ad


def merge_ad(mi, args, out: Path, seeds: list[int]) -> None:
    """Puts the AD run's figures (OUT/ad/summary.json) into every seed's summary.json."""
    ad_file = out / "ad" / "summary.json"
    if not ad_file.exists():
        return
    keys = ad_keys(json.loads(ad_file.read_text()))
    for s in seeds:
        f = out / f"seed-{s}" / "summary.json"
        if f.exists():
            summary = {**json.loads(f.read_text()), **keys}
            f.write_text(json.dumps(summary, indent=2) + "\n")
            if mi is not None:
                replot(mi, args, f.parent, summary)
            else:
                replot(SimpleMi(summary.get("mitsuba_version", "3")), args, f.parent, summary)


class SimpleMi:
    def __init__(self, version):
        self.__version__ = version


if __name__ == "__main__":
    raise SystemExit(main())
