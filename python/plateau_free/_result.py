"""What :func:`plateau_free.minimize` and :attr:`plateau_free.AskTell.result` return:
:class:`OptimizeResult` and :class:`History`, made from the raw results of the Rust side."""

from __future__ import annotations

import inspect
import math
from typing import Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

from ._types import _FloatArray


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
        Whether the run ended by its own test of success, as in scipy: True when ``fun``
        reached ``target`` or the search converged (``restarts=False``); False when the budget
        or the iterations ran out (the run could not tell whether ``x`` is a minimum) or the
        callback, Ctrl-C or an exception stopped the run.
    status : int
        As scipy's: 0 success (target reached, converged, done); 1 the budget spent
        (adaptive, polished) or all iterations done (the paper's loop, which never tests for
        convergence); 2 interrupted (Ctrl-C: ``KeyboardInterrupt`` raised by ``fun`` or by the
        signal); 3 ended by an exception (the result an exception carries as
        ``exc.result``); 99 stopped by the callback (it returned a true value or raised
        ``StopIteration``).
    message : str
        What happened, in words: ``'target reached'``, ``'converged'``, ``'budget spent:
        ...'``, ``'completed N iterations ...'``, ``'stopped by the callback ...'`` or
        scipy's ``'`callback` raised `StopIteration`.'``; a run of the paper's loop continued
        from a checkpoint file says so first (``'restored from the finished checkpoint PATH:
        ...'``, ``'continued from the checkpoint PATH at iteration k: ...'``).
    restarts : int or None
        Adaptive and polished only: restarts of the search distribution (None when stopped by
        the callback).
    sigma : float or None
        Adaptive and polished only: the spread at the end (None when stopped by the callback).
    history : History, SearchHistory or None
        The paper's loop: per-iteration records (:class:`History`). Adaptive, polished: the
        best value, the spread and the evaluations after each iteration
        (:class:`SearchHistory`; :func:`plateau_free.plot_history` draws it). None from
        :attr:`AskTell.result` of the adaptive search.
    nfail : int
        Failed evaluations (NaN, an infinity, an exception raised by ``fun``) that the run
        went on after (``on_failure='continue'``).
    seed : int
        The seed the run used (drawn afresh for ``seed=None``).
    from_checkpoint : bool
        Whether the run was read from the checkpoint file (``minimize(...,
        checkpoint=path)``) instead of being run whole by this call.
    """

    x: _FloatArray
    fun: float
    nit: int
    nfev: int
    success: bool
    status: int
    message: str
    history: Optional[Union[History, SearchHistory]]
    nfail: int
    seed: int
    restarts: Optional[int]
    sigma: Optional[float]
    from_checkpoint: bool

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
    """Per-iteration records of a :func:`minimize` run of the paper's loop: arrays of the last
    ``keep_history`` iterations (default a million; all of them in a shorter run).

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
        The parameters after each iteration, shape ``(len(history), *x0.shape)``, when
        ``record_x=True``; otherwise None.
    dropped : int
        The iterations before these, no longer kept (``nit = dropped + len(history)``).
    """

    __slots__ = ("sigma", "grad_norm", "fun", "nfev", "x", "dropped")

    def __init__(
        self,
        sigma: _FloatArray,
        grad_norm: _FloatArray,
        fun: _FloatArray,
        nfev: npt.NDArray[np.uint64],
        x: Optional[_FloatArray] = None,
        dropped: int = 0,
    ) -> None:
        self.sigma = sigma
        self.grad_norm = grad_norm
        self.fun = fun
        self.nfev = nfev
        self.x = x
        self.dropped = dropped

    def __len__(self) -> int:
        return len(self.sigma)

    def __repr__(self) -> str:
        recorded = "recorded" if self.x is not None else "not recorded"
        dropped = f", {self.dropped} earlier dropped" if self.dropped else ""
        return f"History({len(self)} iterations{dropped}, x {recorded})"


class SearchHistory:
    """The adaptive search's record of a :func:`minimize` run (``method='adaptive'`` or
    ``'polished'``): one row per iteration (a generation, or an estimate of the paper's loop
    before the polish) while there is room, then evenly thinned (the library's
    ``lifecycle::Trace``): between ``keep_history`` and twice as many rows over the whole run,
    the last iteration's last.

    Attributes
    ----------
    nfev : numpy.ndarray
        Evaluations of ``fun`` so far, after each iteration.
    fun : numpy.ndarray
        The best value seen so far (inf before any finite value).
    sigma : numpy.ndarray
        The search distribution's overall spread after the iteration (NaN where the run has
        none, as in the paper's loop of ``'polished'``).
    dropped : int
        The iterations not kept.
    """

    __slots__ = ("nfev", "fun", "sigma", "dropped")

    def __init__(
        self,
        nfev: npt.NDArray[np.uint64],
        fun: _FloatArray,
        sigma: _FloatArray,
        dropped: int = 0,
    ) -> None:
        self.nfev = nfev
        self.fun = fun
        self.sigma = sigma
        self.dropped = dropped

    def __len__(self) -> int:
        return len(self.nfev)

    def __repr__(self) -> str:
        dropped = f", {self.dropped} earlier dropped" if self.dropped else ""
        return f"SearchHistory({len(self)} iterations{dropped})"


# How a run ended -> (success, status): scipy's meaning (0 success, 1 a limit reached, 99 the
# callback).
_ENDINGS = {
    "target reached": (True, 0),
    "converged": (True, 0),
    "stalled": (True, 0),
    "done": (True, 0),
    "budget spent": (False, 1),
    "iterations done": (False, 1),
    "interrupted": (False, 2),
    "raised": (False, 3),
    "callback": (False, 99),
}


def _callback_message(how: Optional[str], nit: int) -> str:
    """The message of a run the callback stopped: ``how`` is ``'raised'`` (StopIteration, with
    scipy's message) or ``'returned'`` (a true value)."""
    if how == "raised":
        return "`callback` raised `StopIteration`."
    return f"stopped by the callback (it returned a true value) after iteration {nit}"


def _adaptive_result(
    raw: dict[str, Any], budget: int, callback_stop: Optional[str] = None
) -> OptimizeResult:
    """``method='adaptive'``'s (and ``'polished'``'s) result from the raw results of the Rust
    side; ``budget`` the run's (for the message), ``callback_stop`` how the callback stopped
    it."""
    stop = str(raw["stop"])
    nit, nfev = int(raw["nit"]), int(raw["nfev"])
    success, status = _ENDINGS.get(stop, (True, 0))
    message = stop
    if stop == "callback":
        message = _callback_message(callback_stop, nit)
    elif stop == "budget spent":
        message = f"budget spent: {nfev} of at most {budget} evaluations; x is the best point seen"
    elif stop == "stalled":
        message = (
            f"stalled: the best value stopped improving (stop_when_stalled), after {nfev} of at "
            f"most {budget} evaluations; x is the best point seen"
        )
    return OptimizeResult(
        x=raw["x"],
        fun=float(raw["fun"]),
        nit=nit,
        nfev=nfev,
        success=success,
        status=status,
        message=message,
        restarts=raw["restarts"],
        sigma=raw["sigma"],
        history=None,
    )


def _stopped_result(
    raw: dict[str, Any],
    method: str,
    stop: str,
    callback_stop: Optional[str],
    error: Optional[BaseException],
    final_value: Optional[float],
) -> OptimizeResult:
    """The result of a run stopped before its end: by the callback, Ctrl-C
    (``'interrupted'``) or an exception (``'raised'``, ``error``). The adaptive search's best
    point so far; the paper loop's last iterate (with ``final_value``, ``fun`` at it, when the
    callback stopped it)."""
    if method == "plateau":
        result = _paper_result(raw, final_value)
        where = "x is the last iterate"
    else:
        result = OptimizeResult(
            x=raw["x"], fun=float(raw["fun"]), nit=int(raw["nit"]), nfev=int(raw["nfev"]),
            restarts=None, sigma=None, history=None,
        )  # fmt: skip
        where = "x is the best point seen"
    nit, nfev = int(result["nit"]), int(result["nfev"])
    if stop == "callback":
        message = _callback_message(callback_stop, nit)
    elif stop == "interrupted":
        message = f"interrupted (KeyboardInterrupt) after {nfev} evaluations; {where}"
    else:
        message = f"ended by {error!r} after {nfev} evaluations; {where}"
    success, status = _ENDINGS[stop]
    result.update(success=success, status=status, message=message)
    return result


def _paper_result(raw: dict[str, Any], final_value: Optional[float]) -> OptimizeResult:
    """The paper loop's result from the raw results of the Rust side (a run that completed
    its iterations, or the state of one stopped early: :func:`_stopped_result` writes its
    ending); ``final_value`` is ``fun`` at the final ``x`` when evaluated (else ``fun`` is the
    last iteration's mean)."""
    history = History(
        sigma=raw["sigma"],
        grad_norm=raw["grad_norm"],
        fun=raw["fun"],
        nfev=raw["nfev_history"],
        x=raw.get("x_history"),
        dropped=int(raw.get("dropped", 0)),
    )
    nit = int(raw["nit"])
    nfev = int(raw["nfev"])
    if final_value is not None:
        value = float(final_value)
        nfev += 1
    else:
        value = float(history.fun[-1]) if len(history) else math.nan
    message = f"completed {nit} iterations (the iteration limit: the paper's loop does not test for convergence)"
    success, status = _ENDINGS["iterations done"]
    return OptimizeResult(
        x=raw["x"],
        fun=value,
        nit=nit,
        nfev=nfev,
        success=success,
        status=status,
        message=message,
        history=history,
        from_checkpoint=False,
    )


def _wants_intermediate_result(callback: Callable[..., Any]) -> bool:
    try:
        parameters = inspect.signature(callback).parameters
    except (TypeError, ValueError):
        return False
    return list(parameters) == ["intermediate_result"]
