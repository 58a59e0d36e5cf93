""":func:`least_squares`: the vector method, for a ``fun`` that returns many numbers (a
residual image, per-pixel losses) instead of one."""

from __future__ import annotations


import numbers
from typing import Any, Callable, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import _native
from ._result import OptimizeResult
from ._types import _FloatArray

_Sparsity = Union[None, Sequence[Tuple[int, int]], npt.ArrayLike]


def _count(name: str, value: object) -> int:
    """A whole number option (not a bool), as int; ValueError naming it otherwise."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} = {value!r} is invalid: must be a whole number")
    return int(value)


def _real(name: str, value: object) -> float:
    """A real option (not a bool), as float; ValueError naming it otherwise."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} = {value!r} is invalid: must be a real number")
    return float(value)


def _outputs(fun: Callable[..., Any], x: _FloatArray, m: Optional[int]) -> _FloatArray:
    """``fun(x)`` as a flat float64 array of ``m`` values (any ``m`` for the first call)."""
    r = np.asarray(fun(x.copy()), dtype=np.float64).ravel()
    if r.size == 0:
        raise ValueError("fun returned an empty array: it must return at least one value")
    if m is not None and r.size != m:
        raise ValueError(f"fun returned {r.size} values at this point, {m} at x0: the count must not change")
    bad = np.flatnonzero(~np.isfinite(r))
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"fun returned {r[k]!r} as value {k} at x = {x!r}: every value must be finite")
    return r


def _pairs(sparsity: _Sparsity, m: int, n: int) -> Optional[list[tuple[int, int]]]:
    """The pattern as (output, parameter) pairs; None: dense."""
    if sparsity is None:
        return None
    a = np.asarray(sparsity)
    if a.dtype == np.bool_:
        if a.shape != (m, n):
            raise ValueError(f"sparsity: a mask must have shape (outputs, parameters) = {(m, n)}, got {a.shape}")
        rows, cols = np.nonzero(a)
        return [(int(i), int(j)) for i, j in zip(rows, cols)]
    if a.ndim != 2 or a.shape[1] != 2 or not np.issubdtype(a.dtype, np.integer):
        raise ValueError(
            "sparsity must be None, a boolean mask of shape (outputs, parameters), or a sequence of "
            f"(output, parameter) integer pairs; got an array of shape {a.shape} and type {a.dtype}"
        )
    if (a < 0).any():
        raise ValueError(f"sparsity: index {int(a.min())} is negative")
    return [(int(i), int(j)) for i, j in a]


def _start(
    x0: npt.ArrayLike, bounds: Optional[Tuple[npt.ArrayLike, npt.ArrayLike]]
) -> Tuple[_FloatArray, Optional[Tuple[list[float], list[float]]]]:
    """``x0`` as a finite 1-D float64 array inside the box, and the box as lists (None: none)."""
    x = np.asarray(x0, dtype=np.float64)
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"x0 must be a non-empty 1-D array, got shape {x.shape}")
    if not np.isfinite(x).all():
        raise ValueError(f"x0 = {x!r} is invalid: every coordinate must be finite")
    if bounds is None:
        return x, None
    lower, upper = (np.asarray(b, dtype=np.float64).ravel() for b in bounds)
    box = (lower.tolist(), upper.tolist())
    # Lengths that do not match are the Rust side's error, which names them.
    if len(box[0]) == x.size == len(box[1]):
        outside = (x < lower) | (x > upper)
        if outside.any():
            k = int(np.flatnonzero(outside)[0])
            raise ValueError(f"x0[{k}] = {x[k]!r} lies outside the bounds [{box[0][k]!r}, {box[1][k]!r}]")
    return x, box


def _counts(**options: object) -> dict[str, int]:
    """The whole-number options: ``seed`` in [0, 2**64), the others at least 1."""
    counts = {name: _count(name, v) for name, v in options.items()}
    for name, value in counts.items():
        if name != "seed" and value < 1:
            raise ValueError(f"{name} = {value} is invalid: must be at least 1")
    if not 0 <= counts["seed"] < 2**64:
        raise ValueError(f"seed = {counts['seed']} is invalid: must be in [0, 2**64)")
    return counts


def least_squares(
    fun: Callable[[_FloatArray], npt.ArrayLike],
    x0: npt.ArrayLike,
    *,
    budget: int = 1000,
    sigma0: float = 0.1,
    pairs: int = 8,
    memory: int = 8,
    damping: float = 1e-3,
    max_step: float = 1.0,
    acceptance: Literal["descent", "always"] = "descent",
    smoothed_residuals: bool = False,
    sparsity: _Sparsity = None,
    bounds: Optional[Tuple[npt.ArrayLike, npt.ArrayLike]] = None,
    seed: int = 0,
) -> OptimizeResult:
    """Minimise ``sum(fun(x) ** 2)`` for a black-box ``fun`` that returns an array.

    The Rust ``plateau_free::LeastSquares``: each iteration draws ``pairs`` antithetic
    Gaussian perturbations of spread ``sigma`` (annealed over the budget from ``sigma0`` to
    0.01), estimates the Gaussian-smoothed Jacobian of ``fun`` from them by Stein's identity
    (only on the ``sparsity`` pattern: which outputs move with which parameters), and takes a
    damped Gauss-Newton step, at most ``max_step * sigma`` per coordinate, evaluated once and
    taken when it does not increase the sum of squares (``acceptance='descent'``; a tie is
    taken, so a flat ``fun`` does not stop the run) or always (``'always'``). With a sparse
    pattern the Jacobian's noise does not grow with the number of parameters: this is the
    method for a residual image whose pixels each depend on a few parameters.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> array`` of ``m`` finite values (any shape; flattened), the same ``m``
        at every point.
    x0 : array_like
        The start, 1-D, evaluated first.
    budget : int
        The most evaluations of ``fun``, the start's included.
    sparsity : None, bool array of shape (m, n), or sequence of (output, parameter) pairs
        Which parameters each output depends on; None: every output on every parameter.
    bounds : (lower, upper) or None
        A box: every evaluated point is clamped onto it; ``x0`` must lie inside.
    sigma0, pairs, memory, damping, max_step, acceptance, smoothed_residuals, seed
        As the Rust options of the same names (``memory``: how many Jacobian estimates are
        averaged).

    Returns
    -------
    OptimizeResult
        ``x`` (the best point evaluated), ``fun`` (its sum of squares), ``residuals`` (its
        outputs), ``nit`` (steps taken), ``njev`` (Jacobian estimates), ``nfev``,
        ``success`` (False: the run spends its budget and does not test for convergence),
        ``status`` 1, ``message``.

    Examples
    --------
    >>> import numpy as np, plateau_free
    >>> target = np.linspace(0.1, 0.9, 50)
    >>> res = plateau_free.least_squares(lambda x: x - target, np.full(50, 0.5), budget=300,
    ...                                  sparsity=[(i, i) for i in range(50)], seed=1)
    >>> bool(np.abs(res.x - target).max() < 1e-6)
    True
    """
    x, box = _start(x0, bounds)
    if acceptance not in ("descent", "always"):
        raise ValueError(f"acceptance = {acceptance!r} is invalid: expected 'descent' or 'always'")
    if not isinstance(smoothed_residuals, (bool, np.bool_)):
        raise ValueError(f"smoothed_residuals = {smoothed_residuals!r} is invalid: must be True or False")
    counts = _counts(budget=budget, pairs=pairs, memory=memory, seed=seed)
    # The start first (as the run would ask it): its outputs give m.
    r0 = _outputs(fun, x, None)
    m = r0.size
    raw = _native._LeastSquares(
        x.tolist(),
        m,
        _pairs(sparsity, m, x.size),
        counts["budget"],
        _real("sigma0", sigma0),
        counts["pairs"],
        counts["memory"],
        _real("damping", damping),
        _real("max_step", max_step),
        acceptance,
        bool(smoothed_residuals),
        box,
        counts["seed"],
    )
    first = raw.ask()
    assert first is not None  # the budget is at least 1: the start is asked
    raw.tell(r0.tolist())
    while (asked := raw.ask()) is not None:
        points, _seeds = asked
        outputs = np.concatenate([_outputs(fun, p, m) for p in points])
        raw.tell(outputs.tolist())
    best_x, best_fun, residuals, nit, njev, nfev = raw.result()
    return OptimizeResult(
        x=np.asarray(best_x),
        fun=float(best_fun),
        residuals=np.asarray(residuals),
        nit=nit,
        njev=njev,
        nfev=nfev,
        success=False,
        status=1,
        message=f"budget spent: {nfev} of {counts['budget']} evaluations",
    )


__all__ = ["least_squares"]



