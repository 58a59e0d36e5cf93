"""Usable gradients for black-box, plateau-ridden and discontinuous functions.

``plateau`` smooths an objective ``f: R^n -> R`` with a Gaussian in parameter space,

    Q_sigma(x) = E_{tau ~ N(0, sigma^2 I)} f(x + tau),

and estimates ``grad Q_sigma`` by importance-sampled, antithetic Monte Carlo from values of
``f`` alone (Fischer and Ritschel, "Plateau-reduced Differentiable Path Tracing", CVPR 2023).
The smoothed objective has no plateaus; an annealed ``sigma`` and Adam do the rest. The work
runs in Rust with the GIL released; ``fun`` is called back with the GIL held.

The main entry points:

- :class:`PlateauFreeGradient` -- ``PlateauFreeGradient(fun).estimate(x, sigma)``.
- :func:`minimize` -- ``minimize(fun, x0, budget=...)`` runs the library's general-purpose
  search (``plateau::Minimizer``); with ``sigma0``/``lr``/``iterations``, or
  ``method='plateau'``, the paper's loop. Returns an :class:`OptimizeResult`.
- :class:`Annealer` (``paper``, ``constant``, ``exponential``, ``cosine``), :class:`Adam`
  (with bounds), :class:`Sampling` (``Radial``, ``PerCoordinate``, ``Gaussian``).
- :class:`FiniteDifference`, :class:`Spsa` -- the baselines (also in ``plateau.baseline``).
"""

from __future__ import annotations

import enum
import inspect
import json
import math
import os
from typing import Any, Callable, Optional, Union

import numpy as np

from . import _plateau
from ._plateau import (
    PAPER_SIGMA_MIN,
    PAPER_WARMUP,
    Adam,
    Annealer,
    FiniteDifference,
    PlateauFreeGradient,
    Spsa,
)

__all__ = [
    "PAPER_SIGMA_MIN",
    "PAPER_WARMUP",
    "Adam",
    "Annealer",
    "FiniteDifference",
    "History",
    "OptimizeResult",
    "PlateauFreeGradient",
    "Sampling",
    "Spsa",
    "minimize",
]

__version__ = "0.1.0"


class Sampling(str, enum.Enum):
    """The sampler of perturbations (the Rust ``plateau::Sampling``).

    Every place that takes a sampler also takes its value as a string.

    - ``Radial`` (``"radial"``, the default): direction uniform on the sphere, radius
      ``chi_{n+1}``; exact Gaussian smoothing in every dimension, for every ``f``.
    - ``PerCoordinate`` (``"per_coordinate"``): the paper's reference sampler, independent
      Rayleigh offsets per coordinate. Exact for ``n = 1`` and for additively separable ``f``;
      for other ``f`` biased (tens of percent on a 3-D tilted step). Kept to reproduce the paper.
    - ``Gaussian`` (``"gaussian"``): plain evolution strategies, the "no importance sampling"
      ablation; unbiased, higher variance.
    """

    Radial = "radial"
    PerCoordinate = "per_coordinate"
    Gaussian = "gaussian"

    def __str__(self) -> str:
        return self.value


class OptimizeResult(dict):
    """The result of :func:`minimize`, with the fields of ``scipy.optimize.OptimizeResult``.

    Attributes
    ----------
    x : numpy.ndarray
        ``method='adaptive'``: the best point seen. The paper's loop: the parameters after the
        last iteration. Shaped like ``x0``.
    fun : float
        ``fun(x)``: the best value seen (adaptive), or evaluated once after the run (the paper's
        loop, see ``final_evaluation``).
    nit : int
        Iterations completed.
    nfev : int
        Evaluations of ``fun`` in all, the final one included.
    success : bool
        Whether the run ended normally (always True; failures raise).
    status : int
        The paper's loop: 0 all iterations done, 1 stopped by the callback. Adaptive: 0 budget
        spent, 1 stopped by the callback, 2 target reached, 3 converged (``restarts=False``).
    message : str
        What happened, in words (adaptive: the stop reason, ``'budget spent'``,
        ``'target reached'``, ``'converged'`` or ``'stopped by the callback'``).
    restarts : int or None
        Adaptive only: restarts of the search distribution (None when stopped by the callback).
    sigma : float or None
        Adaptive only: the spread at the end (None when stopped by the callback).
    history : History or None
        The paper's loop: per-iteration records. Adaptive: None.
    """

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError as e:
            raise AttributeError(name) from e

    __setattr__ = dict.__setitem__  # type: ignore[assignment]
    __delattr__ = dict.__delitem__  # type: ignore[assignment]

    def __repr__(self) -> str:
        if not self:
            return f"{type(self).__name__}()"
        width = max(map(len, self.keys())) + 1
        lines = []
        for key, value in self.items():
            text = repr(value)
            if isinstance(value, np.ndarray) and value.size > 8:
                text = f"array of shape {value.shape}"
            lines.append(f"{key.rjust(width)}: {text}")
        return "\n".join(lines)

    def __dir__(self) -> list[str]:
        return list(self.keys())


class History:
    """Per-iteration records of a :func:`minimize` run (arrays of length ``nit``).

    Attributes
    ----------
    sigma : numpy.ndarray
        The spread each iteration's gradient was estimated with.
    grad_norm : numpy.ndarray
        The Euclidean norm of each iteration's gradient estimate.
    fun : numpy.ndarray
        The mean of ``fun`` over each iteration's evaluations (at the perturbed points, not
        at ``x``): a noisy estimate of the smoothed objective.
    nfev : numpy.ndarray
        Evaluations of ``fun`` so far, after each iteration.
    x : numpy.ndarray or None
        The parameters after each iteration, shape ``(nit, *x0.shape)``, when
        ``record_x=True``; otherwise None.
    """

    __slots__ = ("sigma", "grad_norm", "fun", "nfev", "x")

    def __init__(
        self,
        sigma: np.ndarray,
        grad_norm: np.ndarray,
        fun: np.ndarray,
        nfev: np.ndarray,
        x: Optional[np.ndarray] = None,
    ) -> None:
        self.sigma = sigma
        self.grad_norm = grad_norm
        self.fun = fun
        self.nfev = nfev
        self.x = x

    def __len__(self) -> int:
        return len(self.sigma)

    def __repr__(self) -> str:
        return f"History({len(self)} iterations, x {'recorded' if self.x is not None else 'not recorded'})"


def _parse_bounds(bounds: Any, shape: tuple[int, ...]) -> tuple[list[float], list[float]]:
    """``(lower, upper)`` lists of ``prod(shape)`` numbers from scipy-style bounds."""
    n = int(np.prod(shape))
    if hasattr(bounds, "lb") and hasattr(bounds, "ub"):  # scipy.optimize.Bounds
        lower = np.broadcast_to(np.asarray(bounds.lb, dtype=float), shape).ravel()
        upper = np.broadcast_to(np.asarray(bounds.ub, dtype=float), shape).ravel()
    else:
        items = list(bounds)
        if len(items) == 2 and all(b is None or np.ndim(b) == 0 for b in items):
            items = [items]  # one (lower, upper) pair for every coordinate
        pairs = []
        for b in items:
            lo, hi = b
            pairs.append((-math.inf if lo is None else lo, math.inf if hi is None else hi))
        array = np.asarray(pairs, dtype=float)
        if array.shape == (1, 2):
            array = np.broadcast_to(array, (n, 2))
        if array.shape != (n, 2):
            raise ValueError(
                f"bounds: expected {n} (lower, upper) pairs (one per coordinate of x0) or a single pair, got {len(pairs)}"
            )
        lower, upper = array[:, 0], array[:, 1]
    for i, (lo, hi) in enumerate(zip(lower, upper)):
        if math.isnan(lo) or math.isnan(hi) or lo > hi:
            raise ValueError(f"bounds[{i}]: lower {lo} > upper {hi} (or not a number)")
    return [float(v) for v in lower], [float(v) for v in upper]


def _wants_intermediate_result(callback: Callable[..., Any]) -> bool:
    try:
        parameters = inspect.signature(callback).parameters
    except (TypeError, ValueError):
        return False
    return list(parameters) == ["intermediate_result"]


def minimize(
    fun: Callable[..., Any],
    x0: Any,
    *,
    budget: Optional[int] = None,
    sigma0: Optional[float] = None,
    iterations: Optional[int] = None,
    lr: Optional[float] = None,
    samples: Optional[int] = None,
    sampling: Optional[str] = None,
    antithetic: Optional[bool] = None,
    seed: int = 0,
    bounds: Any = None,
    annealer: Any = None,
    sigma_min: Optional[float] = None,
    batched: bool = False,
    seeded: bool = False,
    callback: Optional[Callable[..., Any]] = None,
    method: Optional[str] = None,
    target: Optional[float] = None,
    population: Optional[int] = None,
    restarts: bool = True,
    step: Optional[float] = None,
    orthogonal: Optional[bool] = None,
    parallel: Optional[bool] = None,
    record_x: Optional[bool] = None,
    final_evaluation: Optional[bool] = None,
    checkpoint: Optional[Union[str, os.PathLike[str]]] = None,
    checkpoint_every: Optional[int] = None,
) -> OptimizeResult:
    """Minimise ``fun`` from ``x0``: ``minimize(fun, x0, budget=...)`` is the first thing to try.

    Two methods. ``'adaptive'`` (the default when ``budget`` is given and none of ``sigma0``,
    ``lr``, ``iterations`` is) is the library's general-purpose search, ``plateau::minimize`` /
    ``plateau::Minimizer``: a Gaussian search distribution around a mean, ranked values, a
    spread and metric that adapt to ``fun`` (and grow on plateaus), restarts from the best point
    with a doubled population; no step size or learning rate to choose. It returns the best
    point seen. ``'plateau'`` (the default otherwise) is the paper's loop: the plateau-free
    gradient, Adam and an annealed sigma; it returns the last iterate.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> float`` with ``x`` a float64 array shaped like ``x0``; with
        ``seeded=True``, ``fun(x, seed)``; with ``batched=True``, ``fun(X) -> N values`` for
        ``X`` of shape ``(N, *x0.shape)`` (``(N, n)`` for a vector), and
        ``fun(X, seeds)`` when also seeded (``seeds``: ``uint64`` array of length ``N``).
    x0 : array_like
        The start; finite, at least one element.
    budget : int, optional
        A total number of evaluations of ``fun`` (at least 1). Adaptive: the run spends at most
        this many (default ``1000 * x0.size``). The paper's loop: it sets the number of
        iterations, ``budget // samples`` (``// 2n`` for finite differences).
    sigma0 : float, optional
        The initial spread. Adaptive: default a quarter of the mean box width with ``bounds``,
        else ``max(1, max|x0|) / 2``; it adapts from there. The paper's loop: default 0.5 (the
        paper recommends about half the parameter domain); giving it selects the paper's loop
        unless ``method='adaptive'``.
    iterations : int, optional
        Iterations to run; default: the annealer's length if ``annealer`` is an
        :class:`Annealer`, ``budget // evaluations per iteration`` if ``budget`` is given,
        else 400.
    lr : float, optional
        Adam's learning rate (the paper's loop; default 0.02).
    seed : int
        The seed of every random choice: the result is a function of ``fun``, ``x0``, the
        options and the seed alone (adaptive: bit for bit the Rust ``Minimizer``'s).
    samples, sampling, antithetic, orthogonal, parallel
        As for :class:`PlateauFreeGradient` (the paper's loop).
    bounds : optional
        Box bounds: a sequence of ``(lower, upper)`` pairs, one per coordinate (``None`` for no
        bound), one ``(lower, upper)`` pair for all coordinates, or a
        ``scipy.optimize.Bounds``. The paper's loop projects after every step; adaptive
        projects every evaluated point onto the box (finite bounds only, ``x0`` inside).
    annealer : str or Annealer
        ``'paper'`` (sigma0 for half the run, then linear to ``sigma_min``), ``'constant'``,
        ``'exponential'``, ``'cosine'``, or an :class:`Annealer` (then ``sigma0`` and
        ``sigma_min`` are its own).
    sigma_min : float
        The final spread of the decaying schedules (the paper's 0.01).
    batched, seeded : bool
        The form of ``fun`` (see above). Adaptive: a batched ``fun`` is called once per
        iteration with the iteration's whole population; a seeded one gets the same seed for
        every point of an iteration (common random numbers), a new one each iteration.
    callback : callable, optional
        Called after every iteration, as in scipy: ``callback(intermediate_result)`` when its
        only parameter is named ``intermediate_result``, else ``callback(x)``. Returning
        ``True`` stops the run. The paper's loop: an :class:`OptimizeResult` with ``x``,
        ``fun`` -- the iteration's mean value --, ``nit``, ``nfev``, ``sigma``, ``jac`` -- the
        gradient estimate. Adaptive: ``x`` and ``fun`` are the best point and value so far,
        with ``nit`` and ``nfev``.
    method : str, optional
        ``'adaptive'`` (the default with ``budget`` and none of ``sigma0``, ``lr``,
        ``iterations``), ``'plateau'`` (the paper's loop; the default otherwise), or a baseline
        on the paper's loop: ``'fd'`` (central finite differences of step ``step``) or
        ``'spsa'``. The options of the paper's loop alone (``iterations``, ``lr``,
        ``samples``, ``sampling``, ``antithetic``, ``annealer``, ``sigma_min``, ``step``,
        ``orthogonal``, ``parallel``, ``record_x``, ``final_evaluation``) default to None, which
        means the paper loop's default; giving any of them, or ``sigma0``, selects the paper's
        loop when ``method`` is not given, and is a ValueError with ``method='adaptive'``.
    target : float, optional
        Adaptive: stop as soon as ``fun`` reaches ``target`` or below.
    population : int, optional
        Adaptive: the population of the first run (default ``4 + floor(3 ln n)``, at least 2);
        each restart doubles it.
    restarts : bool
        Adaptive: restart from the best point with a doubled population when a run converges or
        stalls while budget remains (default). Off, the run ends with ``'converged'``.
    record_x : bool
        Keep ``x`` after every iteration in ``history.x``.
    final_evaluation : bool
        Evaluate ``fun`` once at the final ``x`` for ``result.fun`` (default). When False,
        ``result.fun`` is the last iteration's mean value.
    checkpoint : str or path, optional
        The paper's loop: a file that keeps the run's state (theta, Adam's moments, the
        iteration, the random streams' position, the history so far and the settings), written
        atomically (temporary file, fsync, rename) every ``checkpoint_every`` iterations, at
        the end, and when ``fun`` or ``callback`` raises (``KeyboardInterrupt`` included). If
        the file exists, the run continues from it: the result is bit for bit that of the run
        never interrupted. A file of other settings, or a damaged one, is a ValueError naming
        the path and the difference, and is not used. Not for ``method='adaptive'`` (its state
        lives inside the Rust ``Minimizer``): a ValueError.
    checkpoint_every : int, optional
        Iterations between checkpoints; 0: only at the end and on an exception (default:
        about every 30 seconds, from the measured time per iteration).

    Returns
    -------
    OptimizeResult
        ``x``, ``fun``, ``nit``, ``nfev``, ``success``, ``status``, ``message``, ``history``;
        adaptive: also ``restarts`` and ``sigma``, and ``history`` is None.

    Raises
    ------
    ValueError
        Bad input (non-finite or empty ``x0``, budget < 1, sigma <= 0, samples 0, odd samples
        with antithetic pairs, bounds with lower > upper, ``x0`` outside the bounds, ...), or ``fun`` returning NaN or an
        infinity, or a batch of the wrong length.
    TypeError
        ``fun`` returning something that is not a number.
    Exception
        Whatever ``fun`` or ``callback`` raises, unchanged (KeyboardInterrupt included: Ctrl-C
        stops the run within one call of ``fun``).
    """
    x0_array = np.asarray(x0, dtype=np.float64)
    if budget is not None and (isinstance(budget, bool) or int(budget) != budget or budget < 1):
        raise ValueError(f"budget = {budget!r} must be a whole number of evaluations, at least 1")
    # The options of the paper's loop alone (None: not given; the defaults are below).
    paper_only = {
        "iterations": iterations,
        "lr": lr,
        "samples": samples,
        "sampling": sampling,
        "antithetic": antithetic,
        "annealer": annealer,
        "sigma_min": sigma_min,
        "step": step,
        "orthogonal": orthogonal,
        "parallel": parallel,
        "record_x": record_x,
        "final_evaluation": final_evaluation,
    }
    if method is None:
        paper = sigma0 is not None or any(v is not None for v in paper_only.values())
        method = "adaptive" if budget is not None and not paper else "plateau"
    method = method.lower()
    if checkpoint_every is not None and (
        isinstance(checkpoint_every, bool)
        or int(checkpoint_every) != checkpoint_every
        or checkpoint_every < 0
    ):
        raise ValueError(f"checkpoint_every = {checkpoint_every!r} must be a whole number >= 0")
    if method == "adaptive":
        if checkpoint is not None:
            raise ValueError(
                "checkpoint: supported by the paper's loop (method='plateau', 'fd' or 'spsa'); "
                "method='adaptive' keeps its state inside the Rust Minimizer"
            )
        given = [name for name, value in paper_only.items() if value is not None]
        if given:
            raise ValueError(
                f"{', '.join(given)}: options of the paper's loop, not of method='adaptive' "
                "(use budget, or method='plateau')"
            )
        return _minimize_adaptive(
            fun,
            x0_array,
            budget=budget,
            seed=seed,
            sigma0=sigma0,
            bounds=bounds,
            target=target,
            population=population,
            restarts=restarts,
            batched=batched,
            seeded=seeded,
            callback=callback,
        )
    sigma0 = 0.5 if sigma0 is None else sigma0
    lr = 0.02 if lr is None else lr
    samples = 2 if samples is None else samples
    sampling = "radial" if sampling is None else sampling
    antithetic = True if antithetic is None else antithetic
    annealer = "paper" if annealer is None else annealer
    sigma_min = PAPER_SIGMA_MIN if sigma_min is None else sigma_min
    step = 1e-3 if step is None else step
    orthogonal = False if orthogonal is None else orthogonal
    parallel = False if parallel is None else parallel
    record_x = False if record_x is None else record_x
    final_evaluation = True if final_evaluation is None else final_evaluation
    if method == "plateau":
        estimator: Any = PlateauFreeGradient(
            fun,
            samples=samples,
            sampling=str(sampling.value if isinstance(sampling, Sampling) else sampling),
            antithetic=antithetic,
            seed=seed,
            batched=batched,
            seeded=seeded,
            orthogonal=orthogonal,
            parallel=parallel,
        )
        per_iteration = samples
    elif method == "fd":
        estimator = FiniteDifference(fun, step=step, seed=seed, batched=batched, seeded=seeded)
        per_iteration = 2 * max(1, x0_array.size)
    elif method == "spsa":
        estimator = Spsa(fun, seed=seed, batched=batched, seeded=seeded)
        per_iteration = 2
    else:
        raise ValueError(
            f"method = {method!r} is not a method: use 'adaptive', 'plateau', 'fd' or 'spsa'"
        )

    if iterations is None:
        if isinstance(annealer, Annealer):
            iterations = annealer.iterations
        elif budget is not None:
            if budget < per_iteration:
                raise ValueError(
                    f"budget = {budget} is less than one iteration ({per_iteration} evaluations)"
                )
            iterations = budget // per_iteration
        else:
            iterations = 400
    if iterations < 1:
        raise ValueError(f"iterations = {iterations} must be at least 1")
    if not isinstance(annealer, Annealer):
        annealer = Annealer(str(annealer), sigma0=sigma0, sigma_min=sigma_min, iterations=iterations)

    parsed_bounds = None if bounds is None else _parse_bounds(bounds, x0_array.shape)
    adam = Adam(lr, bounds=parsed_bounds)
    settings = None
    if checkpoint is not None:
        # What a continued run must share with the run it continues; compared key by key in
        # alphabetical order (the schedule, whose repr holds sigma0 and iterations, after them).
        settings = json.dumps(
            _jsonable(
                {
                    "method": method,
                    "x0": x0_array.ravel().tolist(),
                    "shape": list(x0_array.shape),
                    "samples": samples,
                    "sampling": str(sampling.value if isinstance(sampling, Sampling) else sampling),
                    "antithetic": antithetic,
                    "orthogonal": orthogonal,
                    "seed": seed,
                    "lr": lr,
                    "schedule": repr(annealer),
                    "sigma0": sigma0,
                    "sigma_min": sigma_min,
                    "iterations": iterations,
                    "step": step,
                    "batched": batched,
                    "seeded": seeded,
                    "record_x": record_x,
                    "bounds": parsed_bounds,
                }
            )
        )

    raw_callback = None
    if callback is not None:
        as_result = _wants_intermediate_result(callback)

        def raw_callback(iteration, x, sigma, value, gradient, nfev):  # type: ignore[no-untyped-def]
            if as_result:
                info = OptimizeResult(
                    x=x, fun=value, nit=iteration + 1, nfev=nfev, sigma=sigma, jac=gradient
                )
                return callback(info) is True
            return callback(x) is True

    raw = _plateau._minimize(
        estimator,
        x0_array,
        adam,
        annealer,
        iterations=iterations,
        callback=raw_callback,
        record_x=record_x,
        checkpoint=None if checkpoint is None else os.fspath(checkpoint),
        checkpoint_every=checkpoint_every,
        settings=settings,
    )
    x = raw["x"]
    nfev = int(raw["nfev"])
    history = History(
        sigma=raw["sigma"],
        grad_norm=raw["grad_norm"],
        fun=raw["fun"],
        nfev=raw["nfev_history"],
        x=raw.get("x_history"),
    )
    if final_evaluation:
        value = _evaluate(fun, x, batched=batched, seeded=seeded, seed=seed)
        nfev += 1
    else:
        value = float(history.fun[-1]) if len(history) else math.nan
    nit = int(raw["nit"])
    if raw["stopped_by_callback"]:
        status, message = 1, f"stopped by the callback after iteration {nit}"
    else:
        status, message = 0, f"completed {nit} iterations"
    return OptimizeResult(
        x=x,
        fun=value,
        nit=nit,
        nfev=nfev,
        success=True,
        status=status,
        message=message,
        history=history,
    )


def _jsonable(value: Any) -> Any:
    """``value`` with tuples as lists and non-finite floats as their repr, for JSON."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    return value


_STOP_STATUS = {"budget spent": 0, "callback": 1, "target reached": 2, "converged": 3}


def _minimize_adaptive(
    fun: Callable[..., Any],
    x0: np.ndarray,
    *,
    budget: Optional[int],
    seed: int,
    sigma0: Optional[float],
    bounds: Any,
    target: Optional[float],
    population: Optional[int],
    restarts: bool,
    batched: bool,
    seeded: bool,
    callback: Optional[Callable[..., Any]],
) -> OptimizeResult:
    """``method='adaptive'``: the Rust ``plateau::Minimizer``."""
    raw_callback = None
    if callback is not None:
        as_result = _wants_intermediate_result(callback)

        def raw_callback(nit, x, value, nfev):  # type: ignore[no-untyped-def]
            if as_result:
                return callback(OptimizeResult(x=x, fun=value, nit=nit, nfev=nfev)) is True
            return callback(x) is True

    box = None
    if bounds is not None:
        box = _parse_bounds(bounds, x0.shape)
        for i, (lo, hi) in enumerate(zip(*box)):
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ValueError(
                    f"bounds[{i}] = ({lo}, {hi}): method='adaptive' needs finite bounds "
                    "(the box sets the starting spread and where restarts go)"
                )
    raw = _plateau._minimize_adaptive(
        fun,
        x0,
        budget=None if budget is None else int(budget),
        seed=seed,
        sigma0=sigma0,
        bounds=box,
        target=target,
        population=population,
        restarts=restarts,
        batched=batched,
        seeded=seeded,
        callback=raw_callback,
    )
    stop = raw["stop"]
    nit = int(raw["nit"])
    message = f"stopped by the callback after iteration {nit}" if stop == "callback" else stop
    return OptimizeResult(
        x=raw["x"],
        fun=float(raw["fun"]),
        nit=nit,
        nfev=int(raw["nfev"]),
        success=True,
        status=_STOP_STATUS[stop],
        message=message,
        restarts=raw["restarts"],
        sigma=raw["sigma"],
        history=None,
    )


def _evaluate(fun: Callable[..., Any], x: np.ndarray, *, batched: bool, seeded: bool, seed: int) -> float:
    """``fun(x)`` in whichever form ``fun`` takes."""
    if batched:
        points = x[np.newaxis].copy()
        values = fun(points, np.array([seed], dtype=np.uint64)) if seeded else fun(points)
        return float(np.asarray(values, dtype=np.float64).reshape(-1)[0])
    return float(fun(x.copy(), seed) if seeded else fun(x.copy()))
