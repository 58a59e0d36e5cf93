"""The solvers of the COCO harness, each called as ``solve(f, box)``: ``f`` is the problem
behind a counter that ends the run (raises ``Done``) once the budget is spent or the final
target ``f_opt + 1e-8`` reached; ``box`` is the problem's bounds, its integer variables and
the run's seed. Every solver gets the same budget, the same start (COCO's
``initial_solution``) and the same box; the counter counts every evaluation alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Callable

import numpy as np


class Done(Exception):
    """The budget is spent or the final target reached: the run ends here."""


@dataclass
class Box:
    x0: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    integers: int  # the first ``integers`` variables are integers (bbob-mixint's layout)
    budget: int
    seed: int
    target: float  # f_opt + 1e-8

    @property
    def flags(self) -> list[int]:
        n = self.x0.size
        return [1] * self.integers + [0] * (n - self.integers)

    @property
    def spread(self) -> tuple[float, np.ndarray]:
        """A fifth of the mean box width and each coordinate's width relative to the mean:
        every peer's starting spread (pycma's sigma0 and ``CMA_stds``, CMAwM's sigma and
        covariance)."""
        widths = self.upper - self.lower
        mean = float(np.mean(widths))
        return 0.2 * mean, widths / mean


def minimize_box(f: Callable, box: Box, **options: object) -> None:
    """``plateau_free.minimize`` with the box, nothing declared."""
    import plateau_free

    plateau_free.minimize(f, box.x0, bounds=list(zip(box.lower, box.upper)), budget=box.budget,
                          seed=box.seed, target=box.target, **options)


def minimize_int(f: Callable, box: Box, **options: object) -> None:
    """``plateau_free.minimize`` with the box and ``integrality=`` the integer variables."""
    import plateau_free

    plateau_free.minimize(f, box.x0, bounds=list(zip(box.lower, box.upper)), budget=box.budget,
                          seed=box.seed, target=box.target, integrality=box.flags, **options)


def minimize_plain(f: Callable, box: Box) -> None:
    """``plateau_free.minimize(f, x0, budget=, seed=)``: the README's call, no box."""
    import plateau_free

    plateau_free.minimize(f, box.x0, budget=box.budget, seed=box.seed, target=box.target)


def _pycma(f: Callable, box: Box, integer: bool) -> None:
    import warnings

    with warnings.catch_warnings():  # pycma's note that matplotlib is missing (no plots here)
        warnings.simplefilter("ignore")
        import cma

    sigma0, stds = box.spread
    options = {
        "bounds": [list(box.lower), list(box.upper)],
        "CMA_stds": list(stds),
        "maxfevals": box.budget,
        "ftarget": box.target,
        "seed": box.seed + 1,  # pycma's seed 0 is a random one
        "verbose": -9,
    }
    if integer and box.integers:
        options["integer_variables"] = list(range(box.integers))
    cma.fmin2(f, list(box.x0), sigma0, options, restarts=9, bipop=True)


def pycma_box(f: Callable, box: Box) -> None:
    """pycma 4.5's BIPOP-CMA-ES with the box."""
    _pycma(f, box, integer=False)


def pycma_int(f: Callable, box: Box) -> None:
    """pycma's BIPOP-CMA-ES with the box and ``integer_variables``."""
    _pycma(f, box, integer=True)


def cmawm(f: Callable, box: Box) -> None:
    """``cmaes.CMAwM`` (CMA-ES with margin) with the box and the integer steps, restarted with
    a doubled population (IPOP) whenever it stops, until the budget is spent."""
    from cmaes import CMAwM

    sigma0, stds = box.spread
    steps = np.array(box.flags, dtype=float)
    bounds = np.column_stack([box.lower, box.upper])
    popsize = 4 + int(3 * np.log(box.x0.size))
    restart = 0
    while True:
        es = CMAwM(mean=box.x0.copy(), sigma=sigma0, bounds=bounds, steps=steps,
                   seed=box.seed + restart, population_size=popsize, cov=np.diag(stds**2))
        while not es.should_stop():
            told = []
            for _ in range(es.population_size):
                x_eval, x_tell = es.ask()
                told.append((x_tell, f(x_eval)))
            es.tell(told)
        restart += 1
        popsize *= 2


def ngopt(f: Callable, box: Box) -> None:
    """nevergrad's NGOpt with the box (its bounds, ``set_bounds``) and, on bbob-mixint, the
    integer variables cast to integers (``set_integer_casting``): nevergrad's way of declaring
    them, so NGOpt's selector sees a discrete part; its defaults otherwise."""
    import warnings

    import nevergrad as ng

    flags = np.array(box.flags, dtype=bool)
    x = box.x0.copy()
    with warnings.catch_warnings():  # nevergrad's warnings on its bounds and its own choices
        warnings.simplefilter("ignore")
        parts = {}
        if (~flags).any():
            parts["real"] = ng.p.Array(init=box.x0[~flags].copy()).set_bounds(
                box.lower[~flags], box.upper[~flags])
        if flags.any():
            parts["int"] = ng.p.Array(init=box.x0[flags].copy()).set_bounds(
                box.lower[flags], box.upper[flags]).set_integer_casting()
        param = ng.p.Dict(**parts)
        param.random_state = np.random.RandomState(box.seed)
        opt = ng.optimizers.NGOpt(parametrization=param, budget=box.budget, num_workers=1)
        while True:
            candidate = opt.ask()
            if "real" in parts:
                x[~flags] = candidate.value["real"]
            if "int" in parts:
                x[flags] = candidate.value["int"]
            opt.tell(candidate, f(x))


def random_search(f: Callable, box: Box) -> None:
    """Uniform points in the box, integer variables rounded."""
    rng = np.random.default_rng(box.seed)
    flags = np.array(box.flags, dtype=bool)
    while True:
        x = rng.uniform(box.lower, box.upper)
        x[flags] = np.round(x[flags])
        f(x)


SOLVERS: dict[str, tuple[Callable[[Callable, Box], None], str]] = {
    "minimize-int": (minimize_int, "`minimize` with the box and `integrality=`"),
    "minimize-int-decoded": (partial(minimize_int, metric="decoded"), "`minimize` with the box, `integrality=` and `metric='decoded'`"),
    "minimize-int-full": (partial(minimize_int, metric="full"), "`minimize` with the box, `integrality=` and `metric='full'`"),
    "minimize-box": (minimize_box, "`minimize` with the box"),
    "minimize-box-decoded": (partial(minimize_box, metric="decoded"), "`minimize` with the box and `metric='decoded'`"),
    "minimize-box-full": (partial(minimize_box, metric="full"), "`minimize` with the box and `metric='full'`"),
    "minimize": (minimize_plain, "`minimize(f, x0, budget=, seed=)`"),
    "pycma-int": (pycma_int, "pycma BIPOP-CMA-ES, the box and `integer_variables`"),
    "pycma-box": (pycma_box, "pycma BIPOP-CMA-ES, the box"),
    "cmawm": (cmawm, "`cmaes.CMAwM` (CMA-ES with margin), IPOP restarts"),
    "ngopt": (ngopt, "nevergrad 1.0.12's NGOpt, the box and the integers cast"),
    "random": (random_search, "random search in the box"),
}
# The solvers that declare integer variables: on bbob, which has none, they are the box's.
DECLARES_INTEGERS = {s for s in SOLVERS if s.startswith("minimize-int")} | {"pycma-int", "cmawm"}
# Solvers too slow for the whole grid: run on a subset (``--solvers ngopt --dims 5,10
# --instances 1``), and compared on the page only on the problems they ran.
SUBSET_SOLVERS = ("ngopt",)
