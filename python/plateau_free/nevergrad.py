"""plateau_free's search in `nevergrad <https://facebookresearch.github.io/nevergrad/>`_'s optimizer
registry (``pip install "plateau-free[nevergrad]"``).

Importing this module registers two optimizers, so that nevergrad's own ``minimize``, its
functions and its benchmarks run them by name::

    import nevergrad as ng
    import plateau_free.nevergrad  # registers the names below

    opt = ng.optimizers.registry["PlateauFree"](parametrization=5, budget=2000)
    recommendation = opt.minimize(lambda x: float(np.sum(np.floor(x) ** 2)))

- ``PlateauFree``: :func:`plateau_free.ask_tell` with ``method='adaptive'`` (the adaptive
  Gaussian search with restarts, :func:`plateau_free.minimize`'s default);
- ``PlateauFreePaper``: ``method='plateau'``, the paper's loop (estimated smoothed gradient,
  annealed spread, Adam), with its defaults for the budget.

:class:`ParametrizedPlateauFree` configures either with :func:`plateau_free.ask_tell`'s options
(``ParametrizedPlateauFree(method="adaptive", population=16)``); its ``set_name(name,
register=True)`` registers a configuration of your own.

How nevergrad's ask and tell map to ours: the search runs in nevergrad's standardized space
(the parametrization's initial value is the origin, its scale is 1, so ``sigma0`` defaults to
1). nevergrad asks for one candidate at a time; our run hands out a batch of points (a
generation, or an estimate's perturbed points), which are queued and handed out one by one;
when every point of the batch has been told, the batch's values go to our ``tell`` in the
batch's order, whatever order nevergrad told them in, so that a run with ``num_workers > 1``
(nevergrad's parallel evaluation) is the run of one worker. The next batch depends on the
whole previous one: while a batch's last points are out, further asks (from idle workers) get
the best point so far, whose values are not ours to use. With ``num_workers=1``, asking past a
batch before telling it is an error. The budget is
nevergrad's (required); our run spends at most it, and if it ends before nevergrad stops
asking, the remaining asks are its best point. Our run's seed is drawn from the
parametrization's random state, so ``parametrization.random_state = np.random.RandomState(s)``
(or ``parametrization.random_state.seed(s)``) makes a run repeat exactly. A candidate told
without being asked goes into nevergrad's archive only. The recommendation is our run's best
point (``AskTell.best``, or the result's ``x`` once done).
"""

from __future__ import annotations

import collections
from typing import Any, Deque, Dict, List, Optional, Tuple

import nevergrad as ng  # type: ignore[import-untyped]
import numpy as np
from nevergrad.optimization import base  # type: ignore[import-untyped]

from ._ask_tell import AskTell, ask_tell

__all__ = ["ParametrizedPlateauFree", "PlateauFree", "PlateauFreePaper"]

# The key under which a candidate remembers its place in our batch.
_INDEX = "plateau_free_index"


class _PlateauFreeOptimizer(base.Optimizer):  # type: ignore[misc]
    """A nevergrad optimizer running :func:`plateau_free.ask_tell` (see the module)."""

    no_parallelization = False

    def __init__(
        self,
        parametrization: Any,
        budget: Optional[int] = None,
        num_workers: int = 1,
        method: str = "adaptive",
        options: Optional[Dict[str, Any]] = None,
    ) -> None:
        super().__init__(parametrization, budget=budget, num_workers=num_workers)
        if budget is None:
            raise ValueError("budget = None is invalid: PlateauFree needs nevergrad's budget")
        self._method = method
        self._options: Dict[str, Any] = {"sigma0": 1.0, **(options or {})}
        if method in ("plateau", "paper"):
            # The paper's loop has no sigma0 default of nevergrad's scale to take: its own.
            self._options = dict(options or {})
        self._run: Optional[AskTell] = None
        self._queue: Deque[Tuple[int, np.ndarray]] = collections.deque()
        self._values: List[Optional[float]] = []
        # A run made and dropped, so that a bad option is an error when the optimizer is made;
        # the real run draws its seed at the first ask, after the caller has had the chance to
        # seed the parametrization's random state (nevergrad's way to seed a run).
        self._make_run(0)

    def _make_run(self, seed: int) -> AskTell:
        x0 = np.zeros(self.dimension)
        return ask_tell(
            x0, method=self._method, budget=self.budget, seed=seed, **self._options  # type: ignore[arg-type]
        )

    def _start(self) -> AskTell:
        if self._run is None:
            self._run = self._make_run(int(self._rng.randint(2**31 - 1)))
        return self._run

    def _internal_ask_candidate(self) -> Any:
        run = self._start()
        if not self._queue:
            if any(v is None for v in self._values):
                if self.num_workers > 1:
                    return self._candidate(self._best(), None)  # an idle worker's filler
                raise RuntimeError(
                    "PlateauFree is sequential with num_workers=1: tell every asked candidate "
                    "before asking more"
                )
            if run.done:
                return self._candidate(self._best(), None)
            points, _seeds = run.ask()
            self._values = [None] * len(points)
            self._queue.extend(enumerate(np.asarray(points, dtype=np.float64)))
        index, point = self._queue.popleft()
        return self._candidate(point, index)

    def _candidate(self, data: np.ndarray, index: Optional[int]) -> Any:
        candidate = self.parametrization.spawn_child().set_standardized_data(data)
        candidate._meta[_INDEX] = index
        return candidate

    def _internal_tell_candidate(self, candidate: Any, loss: float) -> None:
        index = candidate._meta.get(_INDEX)
        if index is None or index >= len(self._values):
            return  # a repeat of the best point after the run ended
        self._values[index] = float(loss)
        told = [v for v in self._values if v is not None]
        if len(told) == len(self._values) and self._run is not None:
            self._values = []
            self._run.tell(told)

    def _internal_tell_not_asked(self, candidate: Any, loss: float) -> None:
        """Not ours to use: the batch's values come from its own points only."""

    def _best(self) -> np.ndarray:
        run = self._start()
        if run.done:
            return np.asarray(run.result.x, dtype=np.float64)
        best = run.best
        return np.zeros(self.dimension) if best is None else np.asarray(best[0], dtype=np.float64)

    def _internal_provide_recommendation(self) -> Optional[np.ndarray]:
        # The paper's loop keeps no best point until it ends: nevergrad's own then.
        if self._run is None or (not self._run.done and self._run.best is None):
            return None
        return self._best()


class ParametrizedPlateauFree(base.ConfiguredOptimizer):  # type: ignore[misc]
    """A configuration of :func:`plateau_free.ask_tell` as a nevergrad optimizer family.

    Parameters
    ----------
    method:
        ``'adaptive'`` (default), ``'plateau'`` (also ``'paper'``) or ``'polished'``.
    **options:
        :func:`plateau_free.ask_tell`'s options but ``x0``, ``budget`` and ``seed``, which
        nevergrad gives (``sigma0`` defaults to 1, nevergrad's scale, for the adaptive search).
    """

    def __init__(self, *, method: str = "adaptive", **options: Any) -> None:
        for name in ("x0", "budget", "seed"):
            if name in options:
                raise ValueError(f"{name} = {options[name]!r} is invalid: nevergrad gives it")
        super().__init__(_PlateauFreeOptimizer, {"method": method, "options": options})


PlateauFree = ParametrizedPlateauFree().set_name("PlateauFree", register=True)
PlateauFreePaper = ParametrizedPlateauFree(method="plateau").set_name(
    "PlateauFreePaper", register=True
)
# Also reachable as attributes, as nevergrad's own optimizers are.
ng.optimizers.PlateauFree = PlateauFree
ng.optimizers.PlateauFreePaper = PlateauFreePaper
