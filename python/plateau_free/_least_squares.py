""":func:`least_squares`: the vector method, for a ``fun`` that returns many numbers (a
residual image, per-pixel losses) instead of one. Its run is :func:`minimize`'s: the library's
driver (:mod:`plateau_free._drive`: failures, Ctrl-C, callback, progress, history, checkpoint,
workers), with the options that both take checked by the same rows of
:data:`plateau_free._options._OPTIONS`."""

from __future__ import annotations

import math
from typing import Any, Callable, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import _native
from ._checks import _box, _count, _flag, _number, _show, _start
from ._drive import _fresh_error_if_all_failed, _Run
from ._evaluate import _Evaluator
from ._minimize import _Callback
from ._options import _OPTIONS, _says_instead
from ._result import OptimizeResult, _stopped_result
from ._saved import _setting_pairs, _settings
from ._types import _FloatArray

_Sparsity = Union[None, Sequence[Tuple[int, int]], npt.ArrayLike]

# The options least_squares shares with minimize: their checks are minimize's.
_SHARED = ("budget", "seed", "args", "callback", "on_failure", "workers", "disp", "checkpoint",
           "checkpoint_every", "keep_history")  # fmt: skip

_ACCEPTANCES = ("descent", "always")


def _acceptance(name: str, value: Any) -> str:
    """``acceptance``: ``'descent'`` or ``'always'``."""
    must = f"{name} = {_show(value)} is invalid: expected 'descent' or 'always'"
    if not isinstance(value, str):
        raise _native.OptionTypeError(must)
    if value not in _ACCEPTANCES:
        raise ValueError(must)
    return value


# Its own options' types (their ranges are the library's checks).
_OWN: dict[str, Callable[[str, Any], Any]] = {
    "sigma0": _number,
    "pairs": _count(),
    "memory": _count(),
    "damping": _number,
    "max_step": _number,
    "acceptance": _acceptance,
    "smoothed_residuals": _flag,
}


class _LowerUpper:
    """``bounds=(lower, upper)`` (scipy's ``least_squares`` form) as :func:`_box` reads a
    ``scipy.optimize.Bounds`` (None: open on that side), shown as given."""

    def __init__(self, bounds: Any) -> None:
        try:
            lower, upper = bounds
        except (TypeError, ValueError) as e:
            raise _native.OptionTypeError(
                f"bounds = {_show(bounds)} must be (lower, upper): two arrays of x0's length, or "
                "numbers (None or an infinity: open on that side)"
            ) from e
        self.lb = -np.inf if lower is None else lower
        self.ub = np.inf if upper is None else upper
        self.given = bounds

    def __repr__(self) -> str:
        return repr(self.given)


def _checked(x0: npt.ArrayLike, given: dict[str, Any]) -> tuple[np.ndarray, dict[str, Any]]:
    """``x0`` as a 1-D float64 array and every option checked: the shared ones by
    :func:`minimize`'s rows, the others by :data:`_OWN`; the box as ``(lower, upper)`` lists."""
    x = _start(x0)
    if x.ndim != 1:
        raise ValueError(f"x0 must be a non-empty 1-D array, got shape {x.shape}")
    checked = {"seed": 0, "on_failure": "continue"}
    for name, value in given.items():
        if name == "bounds" or (value is None and name != "seed"):
            continue
        check = _OPTIONS[name].check if name in _SHARED else _OWN[name]
        checked[name] = check(name, value)
    if given.get("bounds") is not None:
        box = given["bounds"]
        checked["bounds"] = _box(box if hasattr(box, "lb") else _LowerUpper(box), x, x0)
    return x, checked


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


class _VectorRun(_Run):
    """A least-squares run on the driver: its result has ``residuals`` and ``njev``, and the
    best point so far is the run's current point whatever ended it."""

    def _result(self, ended: dict[str, Any], error: Optional[BaseException] = None) -> OptimizeResult:
        x, fun, residuals, nit, njev, nfev = self.run.result()
        raw = {"x": np.asarray(x), "fun": fun, "nit": nit, "nfev": nfev}
        result = _vector_result(raw, self.budget, ended["why"], self.callback, error)
        result.update(residuals=np.asarray(residuals), njev=njev)
        return self._finish(result, ended)


def _vector_result(
    raw: dict[str, Any], budget: int, stop: Optional[str], callback: Any, error: Optional[BaseException]
) -> OptimizeResult:
    """The result of a run that spent its budget (``stop`` None) or was stopped."""
    if stop is None:
        message = f"budget spent: {raw['nfev']} of {budget} evaluations"
        return OptimizeResult(**raw, success=False, status=1, message=message)
    how = None if callback is None else callback.stop
    result = _stopped_result(raw, "least_squares", stop, how, error, None)
    del result["restarts"], result["sigma"]
    return result


def _at_start(
    x: np.ndarray, checked: dict[str, Any], evaluate: _Evaluator, stop: str, error: Optional[BaseException]
) -> OptimizeResult:
    """The result of a run stopped at ``x0``, before it could begin: by Ctrl-C
    (``'interrupted'``) or an exception (``'raised'``)."""
    raw = {"x": x, "fun": math.inf, "nit": 0, "nfev": 0}
    result = _vector_result(raw, checked.get("budget", 1000), stop, None, error)
    result.update(residuals=np.zeros(0), njev=0, nfail=evaluate.failures, seed=checked["seed"],
                  from_checkpoint=False, history=None)  # fmt: skip
    return result


@_says_instead
def least_squares(
    fun: Callable[..., npt.ArrayLike],
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
    seed: Optional[int] = 0,
    args: Any = (),
    on_failure: Literal["continue", "raise"] = "continue",
    workers: Any = None,
    disp: bool = False,
    callback: Optional[Callable[..., Any]] = None,
    checkpoint: Any = None,
    checkpoint_every: Optional[int] = None,
    keep_history: Optional[int] = None,
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

    The run is :func:`minimize`'s (the library's driver): failures, Ctrl-C, the callback,
    ``disp``, ``result.history``, ``checkpoint`` and ``workers`` mean what they mean there.

    Parameters
    ----------
    fun : callable
        ``fun(x, *args) -> array`` of ``m`` values (any shape; flattened), the same ``m`` at
        every point; ``x0``'s outputs give ``m``, so ``fun`` must run at ``x0`` (an exception
        there is raised under either policy).
    x0 : array_like
        The start, 1-D, finite, evaluated first.
    budget : int
        The most evaluations of ``fun``, the start's included (default 1000).
    sparsity : None, bool array of shape (m, n), or sequence of (output, parameter) pairs
        Which parameters each output depends on; None: every output on every parameter.
    bounds : (lower, upper) or None
        A box, as scipy's ``least_squares``: arrays of ``x0``'s length or numbers (None or an
        infinity leaves that side open), or a ``scipy.optimize.Bounds``; every evaluated
        point is clamped onto it; ``x0`` must lie inside.
    sigma0, pairs, memory, damping, max_step, acceptance, smoothed_residuals
        As the Rust options of the same names (``memory``: how many Jacobian estimates are
        averaged).
    seed : int or None
        The seed of every random choice (default 0); None: a fresh one, recorded in
        ``result.seed``.
    args : tuple
        Extra arguments: ``fun(x, *args)``.
    on_failure : 'continue' or 'raise'
        A point whose outputs hold NaN or an infinity, or where ``fun`` raised an
        ``Exception``, is a failure. ``'continue'`` (default): a failed pair is left out of
        its Jacobian estimate, a failed step is refused (a shorter one is tried), and
        ``result.nfail`` counts them; a run whose every evaluation raised raises the first
        exception. ``'raise'``: the first failure ends the run with the exception (a
        ValueError naming the point for NaN or an infinity), ``exc.result`` holding the
        result so far.
    workers : int, Executor or callable, optional
        Where an iteration's points are evaluated, as :func:`minimize`'s; the result is bit
        for bit the run of one worker.
    disp : bool
        Print the library's progress line every few seconds and at the end.
    callback : callable, optional
        After every step taken: ``callback(intermediate_result)`` (``x``, ``fun``, ``nit``,
        ``nfev``) when its only parameter has that name, else ``callback(x)``; a true value
        or ``StopIteration`` stops the run (status 99).
    checkpoint, checkpoint_every, keep_history
        As :func:`minimize`'s. A run resumed from a checkpoint evaluates ``x0`` once more
        (its outputs give ``m``) and then ends bit for bit as the run left alone.

    Returns
    -------
    OptimizeResult
        ``x`` (the current point: the best evaluated with ``acceptance='descent'``), ``fun``
        (its sum of squares), ``residuals`` (its outputs), ``nit`` (steps taken), ``njev``
        (Jacobian estimates), ``nfev``, ``nfail``, ``seed``, ``from_checkpoint``,
        ``history`` (a :class:`SearchHistory` of the steps), ``success`` (False: the run
        spends its budget and does not test for convergence), ``status`` (1 budget spent, 2
        Ctrl-C, 3 an exception, 99 the callback, as :func:`minimize`'s), ``message``.

    Raises
    ------
    ValueError
        A bad option, naming it (an :class:`OptionTypeError`, also a TypeError, for one of
        the wrong type); a bad ``x0`` or ``sparsity``; ``fun`` returning an empty array or
        another count than at ``x0``; under ``on_failure='raise'``, a non-finite output.
    Exception
        Whatever ``fun`` raises at ``x0``, or anywhere under ``on_failure='raise'``; whatever
        ``callback`` raises; with ``exc.result`` the result so far once the run has begun.

    Examples
    --------
    >>> import numpy as np, plateau_free
    >>> target = np.linspace(0.1, 0.9, 50)
    >>> res = plateau_free.least_squares(lambda x: x - target, np.full(50, 0.5), budget=300,
    ...                                  sparsity=[(i, i) for i in range(50)], seed=1)
    >>> bool(np.abs(res.x - target).max() < 1e-6)
    True
    """
    if not callable(fun):
        raise _native.OptionTypeError(f"fun = {_show(fun)} must be callable")
    given = dict(budget=budget, sigma0=sigma0, pairs=pairs, memory=memory, damping=damping, max_step=max_step,
                 acceptance=acceptance, smoothed_residuals=smoothed_residuals, bounds=bounds, seed=seed, args=args,
                 on_failure=on_failure, workers=workers, disp=disp, callback=callback, checkpoint=checkpoint,
                 checkpoint_every=checkpoint_every, keep_history=keep_history)  # fmt: skip
    x, checked = _checked(x0, given)
    _native_run(x, checked, 1, None)  # the library's checks of the options, before any evaluation
    evaluate = _Evaluator(
        fun, args=checked.get("args", ()), workers=checked.get("workers", 1),
        on_failure=checked["on_failure"], outputs=0,
    )  # fmt: skip
    try:
        # The start first (as the run asks it): its outputs give m.
        r0 = evaluate(x[np.newaxis], np.zeros(1, dtype=np.uint64))
    except KeyboardInterrupt:
        evaluate.close()
        return _at_start(x, checked, evaluate, "interrupted", None)
    except BaseException as e:
        evaluate.close()
        setattr(e, "result", _at_start(x, checked, evaluate, "raised", e))
        raise
    try:
        raw = _native_run(x, checked, r0.size, _pairs(sparsity, r0.size, x.size))
    except BaseException:
        evaluate.close()
        raise
    raw.ask()  # the start, which the budget (at least 1) always pays for
    try:
        raw.tell(r0.tolist())  # refused under on_failure='raise' if not finite
    except ValueError as e:
        evaluate.close()
        setattr(e, "result", _at_start(x, checked, evaluate, "raised", e))
        raise
    return _run(fun, x, checked, raw, evaluate, r0.size)


def _native_run(x: np.ndarray, checked: dict[str, Any], outputs: int, pairs: Any) -> Any:
    """The Rust run from ``x`` for ``outputs`` outputs (``pairs``: the sparsity pattern's
    ``(output, parameter)`` pairs, None for dense), its options checked by the library."""
    return _native._LeastSquares(
        x.tolist(), outputs, pairs, checked.get("budget", 1000),
        checked.get("sigma0", 0.1), checked.get("pairs", 8), checked.get("memory", 8),
        checked.get("damping", 1e-3), checked.get("max_step", 1.0), checked.get("acceptance", "descent"),
        checked.get("smoothed_residuals", False), checked.get("bounds"), checked["seed"],
        checked["on_failure"],
    )  # fmt: skip


def _run(fun: Any, x: np.ndarray, checked: dict[str, Any], raw: Any, evaluate: _Evaluator, m: int) -> OptimizeResult:
    """The run ``raw`` (its start told, ``m`` outputs a point) to its end on the driver."""
    settings = None
    if checked.get("checkpoint") is not None:
        settings = _setting_pairs(_settings(fun, x, "least_squares", checked, {"outputs": m}))
    callback = _Callback(checked["callback"]) if "callback" in checked else None
    budget = checked.get("budget", 1000)
    run = _VectorRun(raw, evaluate, "least_squares", checked, budget, callback, settings, x)
    result = run.drive()
    _fresh_error_if_all_failed(result, evaluate)
    return result


__all__ = ["least_squares"]
