"""plateau_free's optimizers against nevergrad's NGOpt and CMA on nevergrad's own functions, at
equal budgets, through nevergrad's ``minimize``; writes ``docs/results/nevergrad.md``.

    python -m studies nevergrad      # after pip install "./python[nevergrad]"

Each function is nevergrad's ``ArtificialFunction`` (a random translation, seeded per run, so
the optimum is not at the start), in dimension 10, with a budget of 1000 evaluations (100 per
dimension) and 8 seeds; seed ``s`` seeds both the function's translation and the optimizer's
random state, so every optimizer meets the same 8 functions. Every optimizer runs with its
defaults: nothing is tuned per function or seed. The loss is the function at the optimizer's
recommendation. Also measured: the adapter's cost per evaluation over ``plateau_free.minimize``
on the same run (same seed, same points, a trivial function). About 3 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Callable, Dict, List

import nevergrad as ng
import numpy as np
from nevergrad.functions import ArtificialFunction

import plateau_free
import plateau_free.nevergrad  # noqa: F401  (registers PlateauFree and PlateauFreePaper)

from studies import _page

OPTIMIZERS = ["PlateauFree", "PlateauFreePaper", "NGOpt", "CMA"]
# A smooth bowl, a multimodal one, and two of nevergrad's step functions (zero gradient almost
# everywhere, infinitely many steps towards the optimum).
FUNCTIONS = ["sphere", "rastrigin", "stepellipsoid", "stepdoublelinearslope"]


def run_one(name: str, function: str, dimension: int, budget: int, seed: int) -> float:
    func = ArtificialFunction(function, block_dimension=dimension)
    func.parametrization.random_state.seed(seed)
    param = ng.p.Array(shape=(dimension,))
    param.random_state = np.random.RandomState(seed)
    opt = ng.optimizers.registry[name](parametrization=param, budget=budget)
    recommendation = opt.minimize(func)
    return float(func(recommendation.value))


def summary(losses: List[float], all_losses: Dict[str, List[float]]) -> str:
    """Median, mean (standard error), and the seeds on which the optimizer is best or tied."""
    median = statistics.median(losses)
    mean = statistics.fmean(losses)
    se = statistics.stdev(losses) / math.sqrt(len(losses))
    best = [min(v[i] for v in all_losses.values()) for i in range(len(losses))]
    wins = sum(loss <= b for loss, b in zip(losses, best))
    return f"{median:.3g} | {mean:.3g} ({se:.2g}) | {wins}"


def overhead(dimension: int, budget: int, repeats: int) -> Dict[str, float]:
    """Seconds per evaluation: nevergrad's minimize with PlateauFree against
    plateau_free.minimize, on the same run of a trivial function."""

    def trivial(x: np.ndarray) -> float:
        return float(x[0] * x[0])

    seed = int(np.random.RandomState(0).randint(2**31 - 1))
    times: Dict[str, float] = {"direct": math.inf, "nevergrad": math.inf, "random": math.inf}
    for _ in range(repeats):
        start = time.perf_counter()
        plateau_free.minimize(trivial, np.zeros(dimension), budget=budget, seed=seed, sigma0=1.0)
        times["direct"] = min(times["direct"], (time.perf_counter() - start) / budget)
        param = ng.p.Array(shape=(dimension,))
        param.random_state = np.random.RandomState(0)
        opt = ng.optimizers.registry["PlateauFree"](parametrization=param, budget=budget)
        start = time.perf_counter()
        opt.minimize(trivial)
        times["nevergrad"] = min(times["nevergrad"], (time.perf_counter() - start) / budget)
        # nevergrad's own cost per candidate, with its simplest optimizer.
        opt = ng.optimizers.registry["RandomSearch"](parametrization=param.copy(), budget=budget)
        start = time.perf_counter()
        opt.minimize(trivial)
        times["random"] = min(times["random"], (time.perf_counter() - start) / budget)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--dimension", type=int, default=10)
    parser.add_argument("--budget", type=int, default=1000)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--out", type=Path, default=Path("docs/results/nevergrad.md"))
    args = parser.parse_args()
    started = time.perf_counter()
    rows: List[str] = []
    for function in FUNCTIONS:
        losses: Dict[str, List[float]] = {}
        for name in OPTIMIZERS:
            t = time.perf_counter()
            losses[name] = [
                run_one(name, function, args.dimension, args.budget, seed) for seed in range(args.seeds)
            ]
            print(f"{function:22} {name:17} {time.perf_counter() - t:6.1f} s", flush=True)
        for name in OPTIMIZERS:
            rows.append(f"| {function} | {name} | {summary(losses[name], losses)} |")
    cost = overhead(args.dimension, args.budget, repeats=3)
    cost["load"] = os.getloadavg()[0]
    write(args, rows, cost, time.perf_counter() - started)


def write(args: argparse.Namespace, rows: List[str], cost: Dict[str, float], seconds: float) -> None:
    text = f"""# plateau_free in nevergrad: PlateauFree against NGOpt and CMA

Written by `python -m studies nevergrad` (nevergrad {ng.__version__},
plateau_free {plateau_free.__version__}, Python {platform.python_version()}; {seconds:.0f} s).

nevergrad's `ArtificialFunction`s in dimension {args.dimension} (a random translation per
seed), budget {args.budget} evaluations for every optimizer, {args.seeds} seeds (seed `s`
seeds the function's translation and the optimizer). `PlateauFree` is `plateau_free`'s
adaptive search, `PlateauFreePaper` the paper's loop, both registered by
`import plateau_free.nevergrad`; NGOpt and CMA are nevergrad's. All with their defaults. The
loss is the function at the recommendation (0 at the optimum); "best" counts the seeds on which
the optimizer's loss is the lowest of the four, ties included. The step functions are
`step(s) = exp(int(log s))` of a quadratic (`stepellipsoid`, weights 1 to 1e6) and of
`|sum x|` (`stepdoublelinearslope`): flat almost everywhere.

| function | optimizer | median loss | mean loss (s.e.) | best |
|---|---|---|---|---|
""" + "\n".join(rows) + f"""

Cost of the adapter: nevergrad's `minimize` with `PlateauFree` takes
{cost['nevergrad'] * 1e6:.1f} us per evaluation of a trivial function, `plateau_free.minimize`
on the same run {cost['direct'] * 1e6:.1f} us: {(cost['nevergrad'] - cost['direct']) * 1e6:.1f} us
per evaluation more (best of 3 runs of {args.budget} evaluations in dimension {args.dimension}; load
average {cost['load']:.1f} on {os.cpu_count()} cores while measuring: the times are those of a
shared machine).
Nearly all of it is nevergrad's own bookkeeping of each candidate (its `Parameter` objects and
archive): its `RandomSearch`, which computes next to nothing, takes
{cost['random'] * 1e6:.1f} us per evaluation on the same function and budget.
"""
    _page.write(args.out, text)
    print(text)


if __name__ == "__main__":
    main()
