"""The large-scale evolution strategies of pypop7 as peers of ``docs/results/large-scale.md``:
runs on the texture task and on bbob-largescale, called by ``run.py``.

pypop7 (PyPI ``pypop7``, pinned in ``requirements.txt``) implements the strategies that lead
COCO's bbob-largescale archive; the arms, by the names the csv files use:

- ``lmcma``: LM-CMA, limited-memory CMA-ES (Loshchilov, Evolutionary Computation 2017);
- ``lmmaes``: LM-MA-ES, limited-memory matrix adaptation (Loshchilov, Glasmachers and Beyer,
  IEEE TEVC 2019);
- ``mmes``: MMES, the mixture model of LM-MA-ES's directions (He, Zhou, Li, Zhang and Shi,
  IEEE TEVC 2021);
- ``vkdcma``: VkD-CMA, covariance restricted to a diagonal plus k vectors, k adapted (Akimoto
  and Hansen, GECCO 2016);
- ``pysepcma``: pypop7's separable CMA-ES (Ros and Hansen, PPSN 2008), beside pycma's;
- ``ARM-box`` (on the texture task): ``ARM`` given the box ``[0, 1]^n``. pypop7's strategies
  take the box only to draw a start when none is given, so the objective is evaluated at the
  point projected onto the box, the repair ``minimize`` makes with ``bounds``.

Each gets the start ``x0`` as its mean, one spread ``sigma`` (a quarter of the box's width: on
the texture task 0.25 of the texels' ``[0, 1]``, pycma's advice, as pycma's sep-CMA-ES arm gets;
on bbob-largescale 2, as that arm gets), its default population and options, and pypop7's
``seed_rng`` = ``seed + 1``. pypop7 calls the objective one point at a time; a run is the best
value of its first ``B`` evaluations, for each budget ``B``, from one run at the largest.
"""

from __future__ import annotations

import importlib
import math
import time
from typing import Callable

import numpy as np

from studies.large_scale.run import Outcome, Recorder, Texture, Vector

CLASSES = {
    "lmcma": ("pypop7.optimizers.es.lmcma", "LMCMA"),
    "lmmaes": ("pypop7.optimizers.es.lmmaes", "LMMAES"),
    "mmes": ("pypop7.optimizers.es.mmes", "MMES"),
    "vkdcma": ("pypop7.optimizers.nes.vkdcma", "VKDCMA"),
    "pysepcma": ("pypop7.optimizers.es.sepcmaes", "SEPCMAES"),
}


class Capped(Exception):
    """The wall-time cap, raised from inside the objective to end a pypop7 run."""


def optimizer(arm: str) -> type:
    module, name = CLASSES[arm]
    cls: type = getattr(importlib.import_module(module), name)
    return cls


def run(
    arm: str,
    fun: Callable[[Vector], float],
    x0: Vector,
    sigma: float,
    budget: int,
    seed: int,
    cap: float,
    lower: float,
    upper: float,
    target: float = -math.inf,
) -> tuple[int, bool]:
    """One run of ``arm`` on ``fun`` from ``x0``, at most ``budget`` evaluations and ``cap``
    wall seconds (``fun`` raises :class:`Capped`): the evaluations made, whether capped."""
    n = x0.size
    count = 0
    t0 = time.perf_counter()

    def counted(x: Vector) -> float:
        nonlocal count
        if time.perf_counter() - t0 > cap:
            raise Capped
        count += 1
        return fun(x)

    problem = {
        "fitness_function": counted,
        "ndim_problem": n,
        "lower_boundary": np.full(n, lower),
        "upper_boundary": np.full(n, upper),
    }
    options = {
        "max_function_evaluations": budget,
        "seed_rng": seed + 1,
        "mean": np.array(x0, dtype=np.float64),
        "sigma": sigma,
        "verbose": False,
        "saving_fitness": 0,
    }
    if math.isfinite(target):
        options["fitness_threshold"] = target
    try:
        optimizer(arm)(problem, options).optimize()
    except Capped:
        return count, True
    return count, False


def texture(arm: str, task: Texture, x0: Vector, budgets: list[int], seed: int, cap: float) -> Outcome:
    """``arm`` on the texture task: the best of the first ``B`` evaluations for each ``B``."""
    rec = Recorder(budgets)
    strategy = arm.removesuffix("-box")
    box = strategy != arm

    def fun(x: Vector) -> float:
        v = task.loss(np.clip(x, 0.0, 1.0)[None, :] if box else x[None, :])
        rec.see(v)
        return float(v[0])

    t0 = time.perf_counter()
    evaluations, capped = run(strategy, fun, x0, 0.25, max(budgets), seed, cap, 0.0, 1.0)
    return Outcome(rec.values(capped), rec.evaluations, time.perf_counter() - t0, capped)


def bbob(arm: str, problem: object, budget: int, target: float, cap: float) -> tuple[int, bool]:
    """``arm`` on a bbob-largescale problem from its initial solution, sigma 2, seed 1 (as
    pycma's arm), stopping at ``target``."""
    p: object = problem
    x0 = np.asarray(p.initial_solution, dtype=np.float64)  # type: ignore[attr-defined]

    def fun(x: Vector) -> float:
        return float(p(x))  # type: ignore[operator]

    return run(arm, fun, x0, 2.0, budget, 0, cap, -5.0, 5.0, target)
