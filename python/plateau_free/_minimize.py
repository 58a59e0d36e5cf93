""":func:`minimize`: every method (the adaptive search, the polish, the paper's loop and its
baselines) as an ask-and-tell run on the library's driver (:mod:`plateau_free._drive`)."""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, Any, Callable, Literal, Optional

import numpy.typing as npt

from . import _native
from ._ask_tell import _native_run
from ._drive import _drive
from ._evaluate import _Evaluator
from ._checks import _show
from ._options import Options, _check_call, _options_doc
from ._result import OptimizeResult, _wants_intermediate_result
from ._saved import _setting_pairs, _settings
from ._types import _FloatArray

if TYPE_CHECKING:
    if sys.version_info >= (3, 11):
        from typing import Unpack
    else:
        from typing_extensions import Unpack

_Method = Literal["adaptive", "plateau", "paper", "polished", "fd", "spsa"]


def minimize(
    fun: Callable[..., Any],
    x0: npt.ArrayLike,
    *,
    method: Optional[_Method] = "adaptive",
    **options: Unpack[Options],
) -> OptimizeResult:
    """(made from _MINIMIZE_DOC and the options' table below)"""
    if not callable(fun):
        raise _native.OptionTypeError(f"fun = {_show(fun)} must be callable")
    chosen, x0_array, checked = _check_call("minimize", method, x0, dict(options))
    run, budget, extra = _native_run(chosen, x0_array, checked)
    settings = None
    if checked.get("checkpoint") is not None:
        settings = _setting_pairs(_settings(fun, x0_array, chosen, checked, extra))
    callback = _Callback(checked["callback"]) if "callback" in checked else None
    workers = checked.get("workers", 1)
    if checked.get("parallel") and workers == 1:
        workers = os.cpu_count() or 1
    evaluate = _Evaluator(
        fun,
        args=checked.get("args", ()),
        batched=checked["batched"],
        seeded=checked["seeded"],
        workers=workers,
        # The baselines have no failure policy: their first failure ends the run.
        on_failure="raise" if chosen in ("fd", "spsa") else checked["on_failure"],
    )
    return _drive(run, evaluate, chosen, checked, budget, callback, settings, x0_array)


_MINIMIZE_DOC = """Minimise ``fun`` from ``x0``: ``minimize(fun, x0)`` is the first thing to try.

    ``method`` chooses the run, never the options given:

    - ``'adaptive'`` (the default) is the library's general-purpose search,
      ``plateau_free::minimize`` / ``plateau_free::Minimizer``: a Gaussian search distribution
      around a mean, ranked values, a spread and metric that adapt to ``fun`` (and grow on
      plateaus), restarts from ``x0`` (from the best point once a run has found it
      again) with a doubled population; no step size or learning rate to choose. It spends
      at most ``budget`` evaluations (default ``1000 * x0.size``) and returns the best point
      seen.
    - ``'plateau'`` (also spelt ``'paper'``) is the paper's loop: the plateau-free gradient,
      Adam and an annealed sigma; it returns the last iterate. ``'fd'`` (central finite
      differences of step ``step``) and ``'spsa'`` are baselines on the same loop.
    - ``'polished'`` (``Minimizer::strategy(Strategy::Paper {..}).polish(..)``) runs the
      paper's loop on the first ``1 - polish`` of ``budget``, then the adaptive search from the
      loop's best point with the loop's last sigma on the rest; it returns the best point seen.

    Each method takes its own options (below); an option that the method does not take is a
    ValueError naming the option, its value and the methods that take it (``samples=4`` with
    the default method is one: give ``method='plateau'``).

    Parameters
    ----------
    fun : callable
        ``fun(x, *args) -> float`` with ``x`` a float64 array shaped like ``x0``; with
        ``seeded=True``, ``fun(x, seed, *args)``; with ``batched=True``, ``fun(X) -> N
        values`` for ``X`` of shape ``(N, *x0.shape)``, and ``fun(X, seeds)`` when also
        seeded (``seeds``: ``uint64`` array of length ``N``).
    x0 : array_like
        The start: an array of finite numbers, at least one, inside ``bounds``.
    method : str
        ``'adaptive'`` (default; None means it too), ``'plateau'``/``'paper'``, ``'polished'``,
        ``'fd'`` or ``'spsa'``.
{options}

    Returns
    -------
    OptimizeResult
        ``x``, ``fun``, ``nit``, ``nfev``, ``success``, ``status``, ``message``, ``history``;
        adaptive and polished: also ``restarts`` and ``sigma``. ``success`` and ``status`` as scipy's:

        ============================================  =========  ======
        how the run ended                             success    status
        ============================================  =========  ======
        ``target`` reached; converged (no restarts)   True       0
        stalled (``stop_when_stalled``)               True       0
        budget spent (adaptive, polished)             False      1
        all iterations done (the paper's loop)        False      1
        Ctrl-C (``KeyboardInterrupt``)                False      2
        an exception (its ``exc.result``)             False      3
        the callback returned a true value or raised  False      99
        ``StopIteration``
        ============================================  =========  ======

        Also ``nfail`` (failed evaluations the run went on after), ``seed`` (the seed used),
        ``from_checkpoint``; adaptive and polished: ``history``, a :class:`SearchHistory`.

    Raises
    ------
    TypeError
        A keyword that is no option, naming the word to use (``maxiter``: ``budget=``);
        ``fun`` returning something that is not a number.
    ValueError
        A bad option, naming it and showing its value: of the wrong type (then an
        :class:`OptionTypeError`, also a TypeError), out of range, or not an option of the
        method; a non-finite or empty ``x0``, ``x0`` outside the bounds; a batch of the wrong
        length; with ``on_failure='raise'``, ``fun`` returning NaN or an infinity.
    Exception
        With ``on_failure='raise'``, whatever ``fun`` raises; whatever ``callback`` raises
        (but ``StopIteration``). The exception carries the result so far as ``exc.result``.
        Ctrl-C does not raise: the run returns its best point so far (status 2).
    """
minimize.__doc__ = _MINIMIZE_DOC.replace("{options}", _options_doc("minimize"))


class _Callback:
    """The user's callback as the Rust side calls it, with scipy's rules: a true value returned
    or ``StopIteration`` raised stops the run; :attr:`stop` records which (``'returned'``,
    ``'raised'``)."""

    def __init__(self, callback: Callable[..., Any]) -> None:
        self.callback = callback
        self.as_result = _wants_intermediate_result(callback)
        self.stop: Optional[str] = None

    def _call(self, info: OptimizeResult) -> bool:
        try:
            answer = self.callback(info if self.as_result else info.x)
        except StopIteration:
            self.stop = "raised"
            return True
        try:
            stops = bool(answer)
        except Exception as e:
            raise ValueError(
                f"callback returned {_show(answer)}, which is neither true nor false: return a "
                "true value (or raise StopIteration) to stop the run, None or False to go on"
            ) from e
        if stops:
            self.stop = "returned"
        return stops

    def paper(
        self,
        iteration: int,
        x: _FloatArray,
        sigma: float,
        value: float,
        gradient: _FloatArray,
        nfev: int,
    ) -> bool:
        """After iteration ``iteration`` (from 0) of the paper's loop."""
        info = OptimizeResult(x=x, fun=value, nit=iteration + 1, nfev=nfev, sigma=sigma, jac=gradient)
        return self._call(info)

    def adaptive(self, nit: int, x: _FloatArray, value: float, nfev: int) -> bool:
        """After iteration ``nit`` of the adaptive search, with the best point so far."""
        return self._call(OptimizeResult(x=x, fun=value, nit=nit, nfev=nfev))
