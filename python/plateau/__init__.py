"""Usable gradients for black-box, plateau-ridden and discontinuous functions.

``plateau`` smooths an objective ``f: R^n -> R`` with a Gaussian in parameter space,

    Q_sigma(x) = E_{tau ~ N(0, sigma^2 I)} f(x + tau),

and estimates ``grad Q_sigma`` by importance-sampled, antithetic Monte Carlo from values of
``f`` alone (Fischer and Ritschel, "Plateau-reduced Differentiable Path Tracing", CVPR 2023).
The smoothed objective has no plateaus; an annealed ``sigma`` and Adam do the rest. The work
runs in Rust with the GIL released; ``fun`` is called back with the GIL held.

The main entry points:

- :class:`PlateauFreeGradient` -- ``PlateauFreeGradient(fun).estimate(x, sigma)``.
- :func:`minimize` -- the optimisation loop; returns an :class:`OptimizeResult`.
- :class:`Annealer` (``paper``, ``constant``, ``exponential``, ``cosine``), :class:`Adam`
  (with bounds), :class:`Sampling` (``Radial``, ``PerCoordinate``, ``Gaussian``).
- :class:`FiniteDifference`, :class:`Spsa` -- the baselines (also in ``plateau.baseline``).
"""

from __future__ import annotations

import enum
import inspect
import math
from typing import Any, Callable, Optional

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
        The parameters after the last iteration, shaped like ``x0``.
    fun : float
        ``fun(x)``, evaluated once after the run (see ``final_evaluation``).
    nit : int
        Iterations completed.
    nfev : int
        Evaluations of ``fun`` in all, the final one included.
    success : bool
        Whether the run ended normally (all iterations, or stopped by the callback).
    status : int
        0: all iterations done; 1: stopped by the callback.
    message : str
        What happened, in words.
    history : History
        Per-iteration records.
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
    sigma0: float = 0.5,
    iterations: Optional[int] = None,
    lr: float = 0.02,
    samples: int = 2,
    sampling: str = "radial",
    antithetic: bool = True,
    seed: int = 0,
    bounds: Any = None,
    annealer: Any = "paper",
    sigma_min: float = PAPER_SIGMA_MIN,
    batched: bool = False,
    seeded: bool = False,
    callback: Optional[Callable[..., Any]] = None,
    budget: Optional[int] = None,
    method: str = "plateau",
    step: float = 1e-3,
    orthogonal: bool = False,
    parallel: bool = False,
    record_x: bool = False,
    final_evaluation: bool = True,
) -> OptimizeResult:
    """Minimise ``fun`` from ``x0`` with the plateau-free gradient, Adam and an annealed sigma.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> float`` with ``x`` a float64 array shaped like ``x0``; with
        ``seeded=True``, ``fun(x, seed)``; with ``batched=True``, ``fun(X) -> N values`` for
        ``X`` of shape ``(N, *x0.shape)`` (``(N, n)`` for a vector), and
        ``fun(X, seeds)`` when also seeded (``seeds``: ``uint64`` array of length ``N``).
    x0 : array_like
        The start; finite, at least one element.
    sigma0 : float
        The initial spread (the paper recommends about half the parameter domain).
    iterations : int, optional
        Iterations to run; default: the annealer's length if ``annealer`` is an
        :class:`Annealer`, ``budget // evaluations per iteration`` if ``budget`` is given,
        else 400.
    lr : float
        Adam's learning rate.
    samples, sampling, antithetic, seed, orthogonal, parallel
        As for :class:`PlateauFreeGradient`.
    bounds : optional
        Box bounds, applied by projection after every step: a sequence of ``(lower, upper)``
        pairs, one per coordinate (``None`` for no bound), one ``(lower, upper)`` pair for all
        coordinates, or a ``scipy.optimize.Bounds``.
    annealer : str or Annealer
        ``'paper'`` (sigma0 for half the run, then linear to ``sigma_min``), ``'constant'``,
        ``'exponential'``, ``'cosine'``, or an :class:`Annealer` (then ``sigma0`` and
        ``sigma_min`` are its own).
    sigma_min : float
        The final spread of the decaying schedules (the paper's 0.01).
    batched, seeded : bool
        The form of ``fun`` (see above).
    callback : callable, optional
        Called after every iteration, as in scipy: ``callback(intermediate_result)`` (an
        :class:`OptimizeResult` with ``x``, ``fun`` -- the iteration's mean value --,
        ``nit``, ``nfev``, ``sigma``, ``jac`` -- the gradient estimate) when its only
        parameter is named ``intermediate_result``, else ``callback(x)``. Returning ``True``
        stops the run.
    budget : int, optional
        A total number of evaluations of ``fun``. For now it sets the number of iterations of
        the paper's schedule (``budget // samples``, ``// 2n`` for finite differences).
    method : str
        ``'plateau'`` (default), or a baseline on the same loop: ``'fd'`` (central finite
        differences of step ``step``) or ``'spsa'``.
    record_x : bool
        Keep ``x`` after every iteration in ``history.x``.
    final_evaluation : bool
        Evaluate ``fun`` once at the final ``x`` for ``result.fun`` (default). When False,
        ``result.fun`` is the last iteration's mean value.

    Returns
    -------
    OptimizeResult
        ``x``, ``fun``, ``nit``, ``nfev``, ``success``, ``status``, ``message``, ``history``.

    Raises
    ------
    ValueError
        Bad input (non-finite or empty ``x0``, sigma <= 0, samples 0, odd samples with
        antithetic pairs, bounds with lower > upper, ...), or ``fun`` returning NaN or an
        infinity, or a batch of the wrong length.
    TypeError
        ``fun`` returning something that is not a number.
    Exception
        Whatever ``fun`` or ``callback`` raises, unchanged (KeyboardInterrupt included: Ctrl-C
        stops the run within one call of ``fun``).
    """
    x0_array = np.asarray(x0, dtype=np.float64)
    method = method.lower()
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
        raise ValueError(f"method = {method!r} is not a method: use 'plateau', 'fd' or 'spsa'")

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

    adam = Adam(lr, bounds=None if bounds is None else _parse_bounds(bounds, x0_array.shape))

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


def _evaluate(fun: Callable[..., Any], x: np.ndarray, *, batched: bool, seeded: bool, seed: int) -> float:
    """``fun(x)`` in whichever form ``fun`` takes."""
    if batched:
        points = x[np.newaxis].copy()
        values = fun(points, np.array([seed], dtype=np.uint64)) if seeded else fun(points)
        return float(np.asarray(values, dtype=np.float64).reshape(-1)[0])
    return float(fun(x.copy(), seed) if seeded else fun(x.copy()))
