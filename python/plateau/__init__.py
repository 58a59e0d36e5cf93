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
  ``method='plateau'``, the paper's loop; ``method='polished'``, the paper's loop and then the
  adaptive search. Returns an :class:`OptimizeResult`.
- :class:`Annealer` (``paper``, ``constant``, ``exponential``, ``cosine``), :class:`Adam`
  (with bounds), :class:`Sampling` (``Radial``, ``PerCoordinate``, ``Gaussian``).
- :func:`ask_tell` -- the same runs with the points evaluated by the caller:
  ``es = ask_tell(x0, budget=...)``, then ``X, seeds = es.ask()`` and ``es.tell(values)``
  until ``es.done``; ``es.result`` is :func:`minimize`'s result.
- :class:`FiniteDifference`, :class:`Spsa` -- the baselines (also in ``plateau.baseline``).
"""

from __future__ import annotations

import dataclasses
import enum
import inspect
import json
import math
import os
from typing import (
    Any,
    Callable,
    Literal,
    Optional,
    Sequence,
    SupportsFloat,
    Tuple,
    Union,
    cast,
)

import numpy as np
import numpy.typing as npt

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
    "AskTell",
    "FiniteDifference",
    "History",
    "OptimizeResult",
    "PlateauFreeGradient",
    "Sampling",
    "Spsa",
    "ask_tell",
    "minimize",
]

__version__ = "0.1.0"

_FloatArray = npt.NDArray[np.float64]
_SamplingName = Union[Literal["radial", "per_coordinate", "gaussian"], "Sampling", str]
_ScheduleName = Literal["paper", "constant", "exponential", "cosine"]
_Bounds = Union[
    Sequence[Tuple[Optional[SupportsFloat], Optional[SupportsFloat]]],
    Tuple[Optional[SupportsFloat], Optional[SupportsFloat]],
    Any,
]


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


class OptimizeResult(dict[str, Any]):
    """The result of :func:`minimize`, with the fields of ``scipy.optimize.OptimizeResult``.

    Attributes
    ----------
    x : numpy.ndarray
        ``method='adaptive'`` and ``'polished'``: the best point seen. The paper's loop: the parameters after the
        last iteration. Shaped like ``x0``.
    fun : float
        ``fun(x)``: the best value seen (adaptive, polished), or evaluated once after the run (the paper's
        loop, see ``final_evaluation``).
    nit : int
        Iterations completed.
    nfev : int
        Evaluations of ``fun`` in all, the final one included.
    success : bool
        Whether the run ended normally (always True; failures raise).
    status : int
        The paper's loop: 0 all iterations done, 1 stopped by the callback. Adaptive and
        polished: 0 budget spent, 1 stopped by the callback, 2 target reached, 3 converged
        (``restarts=False``).
    message : str
        What happened, in words (adaptive: the stop reason, ``'budget spent'``,
        ``'target reached'``, ``'converged'`` or ``'stopped by the callback'``).
    restarts : int or None
        Adaptive and polished only: restarts of the search distribution (None when stopped by
        the callback).
    sigma : float or None
        Adaptive and polished only: the spread at the end (None when stopped by the callback).
    history : History or None
        The paper's loop: per-iteration records. Adaptive, polished: None.
    """

    x: _FloatArray
    fun: float
    nit: int
    nfev: int
    success: bool
    status: int
    message: str
    history: Optional[History]
    restarts: Optional[int]
    sigma: Optional[float]

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError as e:
            raise AttributeError(name) from e

    __setattr__ = dict.__setitem__
    __delattr__ = dict.__delitem__

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
        sigma: _FloatArray,
        grad_norm: _FloatArray,
        fun: _FloatArray,
        nfev: npt.NDArray[np.uint64],
        x: Optional[_FloatArray] = None,
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


def _adaptive_bounds(
    bounds: Any, shape: tuple[int, ...], method: str = "adaptive"
) -> Optional[tuple[list[float], list[float]]]:
    """The box of ``method='adaptive'`` (or ``'polished'``): :func:`_parse_bounds`, finite
    only."""
    if bounds is None:
        return None
    box = _parse_bounds(bounds, shape)
    for i, (lo, hi) in enumerate(zip(*box)):
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise ValueError(
                f"bounds[{i}] = ({lo}, {hi}): method={method!r} needs finite bounds "
                "(the box sets the starting spread and where restarts go)"
            )
    return box


def _adaptive_options(
    budget: Optional[int],
    seed: int,
    sigma0: Optional[float],
    bounds: Any,
    target: Optional[float],
    population: Optional[int],
    restarts: bool,
    shape: tuple[int, ...],
    paper: Optional[tuple[int, float, float]] = None,
    polish: Optional[float] = None,
) -> _plateau._AdaptiveOptions:
    """The options of ``method='adaptive'`` (and, with ``paper`` and ``polish``, of
    ``method='polished'``) as the Rust side takes them, the same for :func:`minimize` and
    :func:`ask_tell`."""
    return {
        "budget": None if budget is None else int(budget),
        "seed": seed,
        "sigma0": sigma0,
        "bounds": _adaptive_bounds(bounds, shape, "adaptive" if paper is None else "polished"),
        "target": target,
        "population": population,
        "restarts": restarts,
        "paper": paper,
        "polish": polish,
    }


def _is_number(value: Any) -> bool:
    """Whether ``value`` is a real number (an int or a float, numpy's included; not a bool)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_)
    )


def _polished_options(
    sigma0: Optional[float], lr: Optional[float], samples: Optional[int], polish: Optional[float]
) -> tuple[tuple[int, float, float], float]:
    """``method='polished'``'s ``(samples, lr, sigma0)`` of the paper's loop and the polish
    fraction, the defaults (the paper loop's, and a quarter) filled in and checked."""
    defaults = _PaperOptions()
    samples = defaults.samples if samples is None else samples
    lr = defaults.lr if lr is None else lr
    sigma0 = defaults.sigma0 if sigma0 is None else sigma0
    polish = 0.25 if polish is None else polish
    if not _is_number(samples) or int(samples) != samples or samples < 2 or samples % 2:
        raise ValueError(
            f"samples = {samples!r} must be an even whole number, at least 2 (antithetic pairs)"
        )
    for name, value in (("lr", lr), ("sigma0", sigma0)):
        if not _is_number(value) or not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} = {value!r} must be a finite number > 0")
    if not _is_number(polish) or not 0.0 <= polish < 1.0:
        raise ValueError(
            f"polish = {polish!r} must be a fraction of the budget in [0, 1) "
            "(the share the adaptive search gets after the paper's loop)"
        )
    return (int(samples), float(lr), float(sigma0)), float(polish)


def _choose_method(
    method: Optional[str],
    budget: Optional[int],
    sigma0: Optional[float],
    paper_only: dict[str, Any],
    polish: Optional[float] = None,
) -> str:
    """The method of a :func:`minimize` or :func:`ask_tell` call, lower case, after the checks
    that do not depend on it: ``budget`` a whole number, no option of the paper's loop (the
    entries of ``paper_only`` that are not None) with ``method='adaptive'``, only ``lr`` and
    ``samples`` of them and a ``budget`` with ``method='polished'``, ``polish`` with
    ``method='polished'`` alone."""
    if budget is not None and (isinstance(budget, bool) or int(budget) != budget or budget < 1):
        raise ValueError(f"budget = {budget!r} must be a whole number of evaluations, at least 1")
    if method is None:
        paper = sigma0 is not None or any(v is not None for v in paper_only.values())
        method = "adaptive" if budget is not None and not paper else "plateau"
    method = method.lower()
    if method == "adaptive":
        given = [name for name, value in paper_only.items() if value is not None]
        if given:
            raise ValueError(
                f"{', '.join(given)}: options of the paper's loop, not of method='adaptive' "
                "(use budget, or method='plateau')"
            )
    if method == "polished":
        if budget is None:
            raise ValueError(
                "budget: method='polished' needs one (the paper's loop spends the first "
                "1 - polish of it, the adaptive search the rest)"
            )
        given = [
            name
            for name, value in paper_only.items()
            if value is not None and name not in ("lr", "samples")
        ]
        if given:
            raise ValueError(
                f"{', '.join(given)}: options of method='plateau', not of method='polished' "
                "(its paper loop takes sigma0, lr and samples)"
            )
    elif polish is not None and method in ("adaptive", "plateau", "paper", "fd", "spsa"):
        raise ValueError(
            f"polish = {polish!r}: an option of method='polished', not of method={method!r}"
        )
    return method


@dataclasses.dataclass
class _PaperOptions:
    """The paper loop's options, their defaults filled in (``iterations`` may stay None:
    :meth:`schedule` works it out)."""

    sigma0: float = 0.5
    lr: float = 0.02
    samples: int = 2
    sampling: str = "radial"
    antithetic: bool = True
    annealer: Union[str, Annealer] = "paper"
    sigma_min: float = PAPER_SIGMA_MIN
    step: float = 1e-3
    orthogonal: bool = False
    parallel: bool = False
    record_x: bool = False
    final_evaluation: bool = True
    iterations: Optional[int] = None

    @classmethod
    def given(cls, sigma0: Optional[float], paper_only: dict[str, Any]) -> _PaperOptions:
        """The options given (not None), the defaults for the rest."""
        options = cls(**{name: value for name, value in paper_only.items() if value is not None})
        if sigma0 is not None:
            options.sigma0 = sigma0
        options.sampling = str(options.sampling)  # a Sampling's value
        return options

    def schedule(
        self, budget: Optional[int], per_iteration: int, bounds: Any, shape: tuple[int, ...]
    ) -> tuple[int, Annealer, Adam]:
        """The number of iterations (given, the annealer's, ``budget // per_iteration``, or
        400), the annealer and Adam (with ``bounds``)."""
        iterations, annealer = self.iterations, self.annealer
        if iterations is None:
            if isinstance(annealer, Annealer):
                iterations = annealer.iterations
            elif budget is not None:
                if budget < per_iteration:
                    raise ValueError(
                        f"budget = {budget} is less than one iteration "
                        f"({per_iteration} evaluations)"
                    )
                iterations = budget // per_iteration
            else:
                iterations = 400
        if iterations < 1:
            raise ValueError(f"iterations = {iterations} must be at least 1")
        if not isinstance(annealer, Annealer):
            schedule = cast(_ScheduleName, str(annealer))  # a bad name is Annealer's ValueError
            annealer = Annealer(
                schedule, sigma0=self.sigma0, sigma_min=self.sigma_min, iterations=iterations
            )
        adam = Adam(self.lr, bounds=None if bounds is None else _parse_bounds(bounds, shape))
        return iterations, annealer, adam


_STOP_STATUS = {"budget spent": 0, "callback": 1, "target reached": 2, "converged": 3}


def _adaptive_result(raw: dict[str, Any]) -> OptimizeResult:
    """``method='adaptive'``'s result from the raw results of the Rust side."""
    stop = raw["stop"]
    nit = int(raw["nit"])
    return OptimizeResult(
        x=raw["x"],
        fun=float(raw["fun"]),
        nit=nit,
        nfev=int(raw["nfev"]),
        success=True,
        status=_STOP_STATUS[stop],
        message=f"stopped by the callback after iteration {nit}" if stop == "callback" else stop,
        restarts=raw["restarts"],
        sigma=raw["sigma"],
        history=None,
    )


def _paper_result(raw: dict[str, Any], final_value: Optional[float]) -> OptimizeResult:
    """The paper loop's result from the raw results of the Rust side; ``final_value`` is
    ``fun`` at the final ``x`` when evaluated (else ``fun`` is the last iteration's mean)."""
    history = History(
        sigma=raw["sigma"],
        grad_norm=raw["grad_norm"],
        fun=raw["fun"],
        nfev=raw["nfev_history"],
        x=raw.get("x_history"),
    )
    nit = int(raw["nit"])
    nfev = int(raw["nfev"])
    if final_value is not None:
        value = float(final_value)
        nfev += 1
    else:
        value = float(history.fun[-1]) if len(history) else math.nan
    if raw["stopped_by_callback"]:
        status, message = 1, f"stopped by the callback after iteration {nit}"
    else:
        status, message = 0, f"completed {nit} iterations"
    return OptimizeResult(
        x=raw["x"],
        fun=value,
        nit=nit,
        nfev=nfev,
        success=True,
        status=status,
        message=message,
        history=history,
    )


def _wants_intermediate_result(callback: Callable[..., Any]) -> bool:
    try:
        parameters = inspect.signature(callback).parameters
    except (TypeError, ValueError):
        return False
    return list(parameters) == ["intermediate_result"]


def minimize(
    fun: Callable[..., Any],
    x0: npt.ArrayLike,
    *,
    budget: Optional[int] = None,
    sigma0: Optional[float] = None,
    iterations: Optional[int] = None,
    lr: Optional[float] = None,
    samples: Optional[int] = None,
    sampling: Optional[_SamplingName] = None,
    antithetic: Optional[bool] = None,
    seed: int = 0,
    bounds: Optional[_Bounds] = None,
    annealer: Union[_ScheduleName, Annealer, None] = None,
    sigma_min: Optional[float] = None,
    batched: bool = False,
    seeded: bool = False,
    callback: Optional[Callable[..., Any]] = None,
    method: Optional[Literal["adaptive", "plateau", "polished", "fd", "spsa"]] = None,
    target: Optional[float] = None,
    population: Optional[int] = None,
    restarts: bool = True,
    polish: Optional[float] = None,
    step: Optional[float] = None,
    orthogonal: Optional[bool] = None,
    parallel: Optional[bool] = None,
    record_x: Optional[bool] = None,
    final_evaluation: Optional[bool] = None,
    checkpoint: Optional[Union[str, os.PathLike[str]]] = None,
    checkpoint_every: Optional[int] = None,
) -> OptimizeResult:
    """Minimise ``fun`` from ``x0``: ``minimize(fun, x0, budget=...)`` is the first thing to try.

    Two methods and their combination. ``'adaptive'`` (the default when ``budget`` is given
    and none of ``sigma0``, ``lr``, ``iterations`` is) is the library's general-purpose search,
    ``plateau::minimize`` / ``plateau::Minimizer``: a Gaussian search distribution around a
    mean, ranked values, a spread and metric that adapt to ``fun`` (and grow on plateaus),
    restarts from the best point with a doubled population; no step size or learning rate to
    choose. It returns the best point seen. ``'plateau'`` (the default otherwise) is the
    paper's loop: the plateau-free gradient, Adam and an annealed sigma; it returns the last
    iterate. ``'polished'`` (``Minimizer::strategy(Strategy::Paper {..}).polish(..)``) runs the
    paper's loop on the first ``1 - polish`` of ``budget``, then the adaptive search from the
    loop's best point with the loop's last sigma on the rest; it returns the best point seen.

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
        ``iterations``), ``'plateau'`` (the paper's loop; the default otherwise),
        ``'polished'`` (the paper's loop, then the adaptive search; needs ``budget``, takes
        ``sigma0``, ``lr``, ``samples`` -- the loop's, defaults 0.5, 0.02, 2 --, ``polish``,
        ``seed``, ``bounds`` (finite), ``target``, ``population`` and ``restarts`` -- the
        adaptive search's --, ``batched``, ``seeded``, ``callback``; another option of the
        paper's loop is a ValueError), or a baseline on the paper's loop: ``'fd'`` (central
        finite differences of step ``step``) or ``'spsa'``. The options of the paper's loop alone (``iterations``, ``lr``,
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
    polish : float, optional
        ``method='polished'`` alone (a ValueError with another method): the fraction of
        ``budget``, in ``[0, 1)``, that the adaptive search gets after the paper's loop
        (default 0.25; 0: the loop alone, its best point returned).
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
        adaptive and polished: also ``restarts`` and ``sigma``, and ``history`` is None.

    Raises
    ------
    ValueError
        Bad input (non-finite or empty ``x0``, budget < 1, sigma <= 0, samples 0, odd samples
        with antithetic pairs, bounds with lower > upper, ``x0`` outside the bounds, ``polish``
        outside ``[0, 1)``, an option the method does not take, ...), or ``fun`` returning NaN
        or an infinity, or a batch of the wrong length.
    TypeError
        ``fun`` returning something that is not a number.
    Exception
        Whatever ``fun`` or ``callback`` raises, unchanged (KeyboardInterrupt included: Ctrl-C
        stops the run within one call of ``fun``).
    """
    x0_array = np.asarray(x0, dtype=np.float64)
    # The options of the paper's loop alone (None: not given; the defaults are _PaperOptions').
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
    chosen = _choose_method(method, budget, sigma0, paper_only, polish)
    if checkpoint_every is not None and (
        isinstance(checkpoint_every, bool)
        or int(checkpoint_every) != checkpoint_every
        or checkpoint_every < 0
    ):
        raise ValueError(f"checkpoint_every = {checkpoint_every!r} must be a whole number >= 0")
    if chosen in ("adaptive", "polished"):
        if checkpoint is not None:
            raise ValueError(
                "checkpoint: supported by the paper's loop (method='plateau', 'fd' or 'spsa'); "
                f"method={chosen!r} keeps its state inside the Rust Minimizer"
            )
        if chosen == "polished":
            paper, fraction = _polished_options(sigma0, lr, samples, polish)
            options = _adaptive_options(
                budget, seed, None, bounds, target, population, restarts, x0_array.shape,
                paper=paper, polish=fraction,
            )
        else:
            options = _adaptive_options(
                budget, seed, sigma0, bounds, target, population, restarts, x0_array.shape
            )
        return _minimize_adaptive(
            fun, x0_array, options, batched=batched, seeded=seeded, callback=callback
        )
    o = _PaperOptions.given(sigma0, paper_only)
    if chosen == "plateau":
        estimator: Any = PlateauFreeGradient(
            fun,
            samples=o.samples,
            sampling=o.sampling,
            antithetic=o.antithetic,
            seed=seed,
            batched=batched,
            seeded=seeded,
            orthogonal=o.orthogonal,
            parallel=o.parallel,
        )
        per_iteration = o.samples
    elif chosen == "fd":
        estimator = FiniteDifference(fun, step=o.step, seed=seed, batched=batched, seeded=seeded)
        per_iteration = 2 * max(1, x0_array.size)
    elif chosen == "spsa":
        estimator = Spsa(fun, seed=seed, batched=batched, seeded=seeded)
        per_iteration = 2
    else:
        raise ValueError(
            f"method = {chosen!r} is not a method: use 'adaptive', 'plateau', 'polished', 'fd' or 'spsa'"
        )
    iterations, annealer, adam = o.schedule(budget, per_iteration, bounds, x0_array.shape)
    settings = None
    if checkpoint is not None:
        # What a continued run must share with the run it continues; compared key by key in
        # alphabetical order (the schedule, whose repr holds sigma0 and iterations, after them).
        settings = json.dumps(
            _jsonable(
                {
                    "method": chosen,
                    "x0": x0_array.ravel().tolist(),
                    "shape": list(x0_array.shape),
                    "samples": o.samples,
                    "sampling": o.sampling,
                    "antithetic": o.antithetic,
                    "orthogonal": o.orthogonal,
                    "seed": seed,
                    "lr": o.lr,
                    "schedule": repr(annealer),
                    "sigma0": o.sigma0,
                    "sigma_min": o.sigma_min,
                    "iterations": iterations,
                    "step": o.step,
                    "batched": batched,
                    "seeded": seeded,
                    "record_x": o.record_x,
                    "bounds": None if bounds is None else _parse_bounds(bounds, x0_array.shape),
                }
            )
        )

    raw_callback = None
    if callback is not None:
        as_result = _wants_intermediate_result(callback)

        def raw_callback(
            iteration: int,
            x: _FloatArray,
            sigma: float,
            value: float,
            gradient: _FloatArray,
            nfev: int,
        ) -> bool:
            assert callback is not None
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
        record_x=o.record_x,
        checkpoint=None if checkpoint is None else os.fspath(checkpoint),
        checkpoint_every=checkpoint_every,
        settings=settings,
    )
    final = None
    if o.final_evaluation:
        final = _evaluate(fun, raw["x"], batched=batched, seeded=seeded, seed=seed)
    return _paper_result(raw, final)

def _minimize_adaptive(
    fun: Callable[..., Any],
    x0: np.ndarray,
    options: _plateau._AdaptiveOptions,
    *,
    batched: bool,
    seeded: bool,
    callback: Optional[Callable[..., Any]],
) -> OptimizeResult:
    """``method='adaptive'`` and ``'polished'``: the Rust ``plateau::Minimizer``."""
    raw_callback = None
    if callback is not None:
        as_result = _wants_intermediate_result(callback)

        def raw_callback(nit: int, x: _FloatArray, value: float, nfev: int) -> bool:
            assert callback is not None
            if as_result:
                return callback(OptimizeResult(x=x, fun=value, nit=nit, nfev=nfev)) is True
            return callback(x) is True

    raw = _plateau._minimize_adaptive(
        fun, x0, options, batched=batched, seeded=seeded, callback=raw_callback
    )
    return _adaptive_result(raw)


def _evaluate(fun: Callable[..., Any], x: np.ndarray, *, batched: bool, seeded: bool, seed: int) -> float:
    """``fun(x)`` in whichever form ``fun`` takes."""
    if batched:
        points = x[np.newaxis].copy()
        values = fun(points, np.array([seed], dtype=np.uint64)) if seeded else fun(points)
        return float(np.asarray(values, dtype=np.float64).reshape(-1)[0])
    return float(fun(x.copy(), seed) if seeded else fun(x.copy()))


class AskTell:
    """An optimisation run whose points the caller evaluates: ask and tell.

    Made by :func:`ask_tell`. Each :meth:`ask` hands out one iteration's points and their
    seeds; each :meth:`tell` takes their values back, finishes the estimate and takes the
    step. The points can be evaluated anywhere, in any order (a queue, a game engine, a
    render farm). With the options and seed of a :func:`minimize` call, the run and its
    :attr:`result` are bit for bit that call's.

    Examples
    --------
    >>> import numpy as np, plateau
    >>> es = plateau.ask_tell([0.0, 0.0, 0.0], budget=600, seed=3)
    >>> while not es.done:
    ...     X, seeds = es.ask()
    ...     es.tell([float(np.sum((np.round(x) - 1.0) ** 2)) for x in X])
    >>> es.result.fun
    0.0
    """

    __slots__ = ("_raw", "_method")

    def __init__(self, raw: Any, method: str) -> None:
        self._raw = raw
        self._method = method

    @property
    def method(self) -> str:
        """``'adaptive'``, ``'plateau'`` (the paper's loop) or ``'polished'``."""
        return self._method

    @property
    def done(self) -> bool:
        """Whether the run has ended (:attr:`result` is ready; :meth:`ask` has nothing more)."""
        return bool(self._raw.done)

    @property
    def nfev(self) -> int:
        """Evaluations told so far."""
        return int(self._raw.nfev)

    def ask(self) -> tuple[_FloatArray, npt.NDArray[np.uint64]]:
        """The next points and their seeds: ``X`` of shape ``(k, *x0.shape)`` (float64) and
        ``seeds``, a uint64 array of length ``k``.

        The adaptive search asks for one generation (one seed for all its points, a new one
        each generation); the paper's loop for one gradient estimate (one seed per
        antithetic pair) and, last, for its final point alone (with ``seed``);
        ``'polished'`` for the paper loop's, then the adaptive search's. An objective
        with noise of its own should use the seeds (common random numbers): they are the
        seeds a ``seeded=True`` ``fun`` receives from :func:`minimize`.

        Raises
        ------
        ValueError
            Asked twice without a tell in between, or asked after the run has ended.
        """
        out: Optional[tuple[_FloatArray, npt.NDArray[np.uint64]]] = self._raw.ask()
        if out is None:
            raise ValueError("the run has ended: nothing more to ask (see result)")
        return out

    def tell(self, values: npt.ArrayLike) -> None:
        """Tells the values of the asked points, in the order of ``X``: ``k`` floats.

        Raises
        ------
        ValueError
            Nothing asked, the wrong number of values, or a NaN or an infinity (naming the
            evaluation, the value and the point). After a ValueError the same points still
            wait for their values.
        """
        array = np.asarray(values, dtype=np.float64).reshape(-1)
        self._raw.tell(array.tolist())

    @property
    def best(self) -> Optional[tuple[_FloatArray, float]]:
        """``(x, fun)``, the best point told so far and its value (``method='adaptive'`` or
        ``'polished'``); None before the first value and for the paper's loop."""
        best: Optional[tuple[_FloatArray, float]] = self._raw.best()
        return best

    @property
    def result(self) -> OptimizeResult:
        """The result, as :func:`minimize` returns it.

        Raises
        ------
        ValueError
            The run has not ended: ask and tell until :attr:`done`.
        """
        raw = self._raw.result()
        if raw is None:
            raise ValueError(
                f"the run has not ended ({self.nfev} evaluations told): ask and tell until done"
            )
        if self._method in ("adaptive", "polished"):
            return _adaptive_result(raw)
        return _paper_result(raw, raw["final_value"])

    def __repr__(self) -> str:
        state = "done" if self.done else "running"
        return f"AskTell(method={self._method!r}, {state}, {self.nfev} evaluations told)"


def ask_tell(
    x0: npt.ArrayLike,
    *,
    budget: Optional[int] = None,
    method: Optional[Literal["adaptive", "plateau", "paper", "polished"]] = None,
    seed: int = 0,
    sigma0: Optional[float] = None,
    bounds: Optional[_Bounds] = None,
    target: Optional[float] = None,
    population: Optional[int] = None,
    restarts: bool = True,
    polish: Optional[float] = None,
    iterations: Optional[int] = None,
    lr: Optional[float] = None,
    samples: Optional[int] = None,
    sampling: Optional[_SamplingName] = None,
    antithetic: Optional[bool] = None,
    orthogonal: Optional[bool] = None,
    annealer: Union[_ScheduleName, Annealer, None] = None,
    sigma_min: Optional[float] = None,
    record_x: Optional[bool] = None,
    final_evaluation: Optional[bool] = None,
) -> AskTell:
    """:func:`minimize` without ``fun``: an :class:`AskTell` run whose points you evaluate.

    The options, their defaults and the choice of method are :func:`minimize`'s
    (``method='adaptive'``, the default with ``budget`` and none of the paper loop's options,
    ``'plateau'`` -- also spelt ``'paper'`` -- the paper's loop, or ``'polished'``, the
    paper's loop then the adaptive search, with ``polish``). With the same options and
    seed, ``ask_tell(x0, ...).result`` after the loop below is ``minimize(fun, x0, ...)``, bit
    for bit::

        es = plateau.ask_tell(x0, budget=2000, seed=1)
        while not es.done:
            X, seeds = es.ask()                     # (k, *x0.shape) float64, k uint64 seeds
            es.tell([fun(x) for x in X])            # or fun(x, s) for a seeded fun
        result = es.result                           # OptimizeResult, as minimize returns

    The baselines (``method='fd'``, ``'spsa'``), ``callback`` and ``parallel`` are
    :func:`minimize`'s alone: the caller evaluates, and can stop whenever it likes.

    Raises
    ------
    ValueError
        Bad input, as :func:`minimize`.
    """
    x0_array = np.asarray(x0, dtype=np.float64)
    paper_only = {
        "iterations": iterations,
        "lr": lr,
        "samples": samples,
        "sampling": sampling,
        "antithetic": antithetic,
        "orthogonal": orthogonal,
        "annealer": annealer,
        "sigma_min": sigma_min,
        "record_x": record_x,
        "final_evaluation": final_evaluation,
    }
    chosen = _choose_method(method, budget, sigma0, paper_only, polish)
    if chosen == "adaptive":
        options = _adaptive_options(
            budget, seed, sigma0, bounds, target, population, restarts, x0_array.shape
        )
        raw = _plateau._AskTell.adaptive(x0_array, options)
        return AskTell(raw, "adaptive")
    if chosen == "polished":
        paper, fraction = _polished_options(sigma0, lr, samples, polish)
        options = _adaptive_options(
            budget, seed, None, bounds, target, population, restarts, x0_array.shape,
            paper=paper, polish=fraction,
        )
        return AskTell(_plateau._AskTell.adaptive(x0_array, options), "polished")
    if chosen not in ("plateau", "paper"):
        raise ValueError(
            f"method = {chosen!r} is not a method of ask_tell: use 'adaptive', 'plateau' or 'polished' "
            "(the baselines 'fd' and 'spsa' are minimize's alone)"
        )
    o = _PaperOptions.given(sigma0, paper_only)
    # The estimator's own checks, with its messages (it is never evaluated).
    PlateauFreeGradient(
        lambda x: 0.0,
        samples=o.samples,
        sampling=o.sampling,
        antithetic=o.antithetic,
        orthogonal=o.orthogonal,
    )
    iterations, annealer, adam = o.schedule(budget, o.samples, bounds, x0_array.shape)
    raw = _plateau._AskTell.paper(
        x0_array,
        adam,
        annealer,
        iterations,
        samples=o.samples,
        sampling=o.sampling,
        antithetic=o.antithetic,
        orthogonal=o.orthogonal,
        seed=seed,
        record_x=o.record_x,
        final_evaluation=o.final_evaluation,
    )
    return AskTell(raw, "plateau")


def _jsonable(value: Any) -> Any:
    """``value`` with tuples as lists and non-finite floats as their repr, for JSON."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    return value
