""":func:`ask_tell` and :class:`AskTell`: the runs of :func:`plateau_free.minimize` with the points
evaluated by the caller."""

from __future__ import annotations

import math
import sys
from typing import TYPE_CHECKING, Any, Literal, Optional

import numpy as np
import numpy.typing as npt

from . import _native
from ._checks import _show
from ._native import OptionTypeError, PlateauFreeGradient
from ._options import (
    Options,
    _adaptive_options,
    _check_call,
    _options_doc,
    _PaperOptions,
    _polished_options,
)
from ._result import OptimizeResult, _adaptive_result, _paper_result
from ._types import _FloatArray

if TYPE_CHECKING:
    if sys.version_info >= (3, 11):
        from typing import Unpack
    else:
        from typing_extensions import Unpack


class AskTell:
    """An optimisation run whose points the caller evaluates: ask and tell.

    Made by :func:`ask_tell`. Each :meth:`ask` hands out one iteration's points and their
    seeds; each :meth:`tell` takes their values back, finishes the estimate and takes the
    step. The points can be evaluated anywhere, in any order (a queue, a game engine, a
    render farm). With the options and seed of a :func:`minimize` call, the run and its
    :attr:`result` are bit for bit that call's.

    A run's state is a value: it pickles (and ``copy.deepcopy`` copies it) after any
    :meth:`tell` or between an :meth:`ask` and its :meth:`tell`, and the copy goes on bit for
    bit as the uninterrupted run, so that an experiment manager can checkpoint it in its own
    storage.

    Examples
    --------
    >>> import numpy as np, plateau_free
    >>> es = plateau_free.ask_tell([0.0, 0.0, 0.0], budget=600, seed=3)
    >>> while not es.done:
    ...     X, seeds = es.ask()
    ...     es.tell([float(np.sum((np.round(x) - 1.0) ** 2)) for x in X])
    >>> es.result.fun
    0.0
    """

    __slots__ = ("_raw", "_method", "_budget", "_asked", "_policy", "_seed")

    def __init__(self, raw: Any, method: str, budget: int, policy: str, seed: int) -> None:
        self._raw = raw
        self._method = method
        self._budget = budget
        self._policy = policy
        self._seed = seed
        # The points of the last ask, until told (to name the point of a non-finite value).
        self._asked: Optional[_FloatArray] = None

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
        self._asked = out[0]
        return out

    def tell(self, values: npt.ArrayLike) -> None:
        """Tells the values of the asked points, in the order of ``X``: ``k`` floats.

        Raises
        ------
        ValueError
            Nothing asked, the wrong number of values, or (with ``on_failure='raise'``) a NaN
            or an infinity, naming the evaluation, the value and the point. The paper loop's
            final value must be finite under either policy.
            Values that are not real numbers (None, strings that are not numbers, complex
            numbers) are an :class:`OptionTypeError`, a ValueError and a TypeError. After an
            error the same points still wait for their values.
        """
        array = _told(values)
        asked = self._asked
        final = bool(self._raw.final_asked)
        if asked is not None and array.size == len(asked) and (self._policy == "raise" or final):
            # Refused here for every ask (the Rust side refuses them too, but for the paper
            # loop's final point).
            bad = np.flatnonzero(~np.isfinite(array))
            if bad.size:
                k = int(bad[0])
                value = float(array[k])
                text = "NaN" if math.isnan(value) else repr(value)
                point = np.array2string(np.ravel(asked[k]), threshold=8, separator=", ")
                raise ValueError(
                    f"f returned {text} at evaluation {self.nfev + k}, point {point}: tell "
                    "finite values (the asked points still wait for theirs)"
                )
        self._raw.tell(array.tolist())
        self._asked = None

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
            result = _adaptive_result(raw, self._budget)
        else:
            result = _paper_result(raw, raw["final_value"])
        result.update(nfail=int(raw.get("failures", 0)), seed=self._seed, from_checkpoint=False)
        return result

    def __repr__(self) -> str:
        state = "done" if self.done else "running"
        return f"AskTell(method={self._method!r}, {state}, {self.nfev} evaluations told)"


def _told(values: Any) -> _FloatArray:
    """The told values as a flat float64 array: numbers in any sequence or array of ``k``
    elements; OptionTypeError (a ValueError and a TypeError) for what is not real numbers,
    ValueError for an int too large for a float."""
    must = f"values = {_show(values)} must be real numbers, one per asked point in the order of X"
    if values is None or isinstance(values, (str, bytes, bytearray, dict, set)):
        raise OptionTypeError(must)
    try:
        if np.iscomplexobj(values):
            raise TypeError("complex numbers are not real numbers")
        return np.asarray(values, dtype=np.float64).reshape(-1)
    except OverflowError as e:
        raise ValueError(f"{must}: {e}") from e
    except (TypeError, ValueError) as e:
        raise OptionTypeError(f"{must}: {e}") from e


def ask_tell(
    x0: npt.ArrayLike,
    *,
    method: Optional[Literal["adaptive", "plateau", "paper", "polished"]] = "adaptive",
    **options: Unpack[Options],
) -> AskTell:
    """(made from _ASK_TELL_DOC and the options' table)"""
    chosen, x0_array, checked = _check_call("ask_tell", method, x0, dict(options))
    run, budget, _ = _native_run(chosen, x0_array, checked)
    return AskTell(run, chosen, budget, checked["on_failure"], checked["seed"])


_ASK_TELL_DOC = """:func:`minimize` without ``fun``: an :class:`AskTell` run whose points you evaluate.

    The methods, the options each takes, their defaults and their checks are
    :func:`minimize`'s: ``method='adaptive'`` (the default), ``'plateau'`` -- also spelt
    ``'paper'`` -- the paper's loop, or ``'polished'``, the paper's loop then the adaptive
    search, with ``polish`` (``stop_when_stalled``: adaptive and polished); an option of
    another method is a ValueError naming it. With the
    same options and seed, ``ask_tell(x0, ...).result`` after the loop below is
    ``minimize(fun, x0, ...)``, bit for bit::

        es = plateau_free.ask_tell(x0, budget=2000, seed=1)
        while not es.done:
            X, seeds = es.ask()                     # (k, *x0.shape) float64, k uint64 seeds
            es.tell([fun(x) for x in X])            # or fun(x, s) for a seeded fun
        result = es.result                           # OptimizeResult, as minimize returns

    The baselines (``method='fd'``, ``'spsa'``) and the options of the evaluation
    (``args``, ``batched``, ``seeded``, ``callback``, ``workers``, ``parallel``, ``disp``,
    ``checkpoint``) are :func:`minimize`'s alone: the caller evaluates, and can stop (or save
    its own state) whenever it likes. With ``on_failure='continue'`` (the default) NaN and
    infinities may be told: the failed points rank below every finite value.

    Parameters
    ----------
    x0 : array_like
        The start: an array of finite numbers, at least one, inside ``bounds``.
    method : str
        ``'adaptive'`` (default), ``'plateau'``/``'paper'`` or ``'polished'``.
{options}

    Raises
    ------
    ValueError
        Bad input, as :func:`minimize`.
    """
ask_tell.__doc__ = _ASK_TELL_DOC.replace("{options}", _options_doc("ask_tell"))


def _native_run(
    chosen: str, x0: np.ndarray, checked: dict[str, Any]
) -> tuple[_native._AskTell, int, dict[str, Any]]:
    """The Rust ask-and-tell run of ``chosen`` from ``x0`` with the checked options, its budget
    (for the messages) and what a checkpoint must also compare (the paper loop's iterations
    and schedule)."""
    budget = checked.get("budget", 1000 * x0.size)
    if chosen == "adaptive":
        return _native._AskTell.adaptive(x0, _adaptive_options(checked)), budget, {}
    if chosen == "polished":
        return _native._AskTell.adaptive(x0, _polished_options(checked)), budget, {}
    o = _PaperOptions.given(checked)
    if chosen in ("fd", "spsa"):
        per_iteration = 2 * x0.size if chosen == "fd" else 2
        iterations, annealer, adam = o.schedule(checked.get("budget"), per_iteration, checked.get("bounds"))
        run = _native._AskTell.baseline(
            x0,
            adam,
            annealer,
            iterations,
            "fd" if chosen == "fd" else "spsa",
            step=o.step,
            seed=checked["seed"],
            record_x=o.record_x,
            final_evaluation=o.final_evaluation,
            keep_history=o.keep_history,
        )
        return run, budget, {"iterations": iterations, "schedule": repr(annealer)}
    # The estimator's own checks, with its messages (it is never evaluated).
    PlateauFreeGradient(
        lambda x: 0.0,
        samples=o.samples,
        sampling=o.sampling,
        antithetic=o.antithetic,
        orthogonal=o.orthogonal,
    )
    iterations, annealer, adam = o.schedule(checked.get("budget"), o.samples, checked.get("bounds"))
    run = _native._AskTell.paper(
        x0,
        adam,
        annealer,
        iterations,
        samples=o.samples,
        sampling=o.sampling,
        antithetic=o.antithetic,
        orthogonal=o.orthogonal,
        seed=checked["seed"],
        record_x=o.record_x,
        final_evaluation=o.final_evaluation,
        keep_history=o.keep_history,
        on_failure=checked["on_failure"],
    )
    return run, budget, {"iterations": iterations, "schedule": repr(annealer)}
