""":func:`ask_tell` and :class:`AskTell`: the runs of :func:`plateau_free.minimize` with the points
evaluated by the caller."""

from __future__ import annotations

import math
from typing import Any, Literal, Optional, Union

import numpy as np
import numpy.typing as npt

from . import _native
from ._native import Annealer, OptionTypeError, PlateauFreeGradient
from ._options import _adaptive_options, _check_call, _PaperOptions, _polished_options, _show
from ._result import OptimizeResult, _adaptive_result, _paper_result
from ._types import _Bounds, _FloatArray, _SamplingName, _ScheduleName


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

    __slots__ = ("_raw", "_method", "_budget", "_asked")

    def __init__(self, raw: Any, method: str, budget: int) -> None:
        self._raw = raw
        self._method = method
        self._budget = budget
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
            Nothing asked, the wrong number of values, or a NaN or an infinity (naming the
            evaluation, the value and the point; the paper loop's final value included).
            Values that are not real numbers (None, strings that are not numbers, complex
            numbers) are an :class:`OptionTypeError`, a ValueError and a TypeError. After an
            error the same points still wait for their values.
        """
        array = _told(values)
        asked = self._asked
        if asked is not None and array.size == len(asked):
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
            return _adaptive_result(raw, self._budget)
        return _paper_result(raw, raw["final_value"])

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
    budget: Optional[int] = None,
    seed: int = 0,
    sigma0: Optional[float] = None,
    bounds: Optional[_Bounds] = None,
    target: Optional[float] = None,
    population: Optional[int] = None,
    restarts: Optional[bool] = None,
    polish: Optional[float] = None,
    stop_when_stalled: Optional[float] = None,
    iterations: Optional[int] = None,
    lr: Optional[float] = None,
    samples: Optional[int] = None,
    sampling: Optional[_SamplingName] = None,
    antithetic: Optional[bool] = None,
    orthogonal: Optional[bool] = None,
    annealer: Union[_ScheduleName, Annealer, None] = None,
    sigma_min: Optional[float] = None,
    record_x: Optional[bool] = None,
    keep_history: Optional[int] = None,
    final_evaluation: Optional[bool] = None,
) -> AskTell:
    """:func:`minimize` without ``fun``: an :class:`AskTell` run whose points you evaluate.

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

    The baselines (``method='fd'``, ``'spsa'``), ``callback``, ``parallel`` and
    ``checkpoint`` are :func:`minimize`'s alone: the caller evaluates, and can stop (or save
    its own state) whenever it likes.

    Raises
    ------
    ValueError
        Bad input, as :func:`minimize`.
    """
    options = dict(
        budget=budget, seed=seed, sigma0=sigma0, bounds=bounds, target=target,
        population=population, restarts=restarts, polish=polish,
        stop_when_stalled=stop_when_stalled, iterations=iterations, lr=lr,
        samples=samples, sampling=sampling, antithetic=antithetic, orthogonal=orthogonal,
        annealer=annealer, sigma_min=sigma_min, record_x=record_x, keep_history=keep_history,
        final_evaluation=final_evaluation,
    )  # fmt: skip
    chosen, x0_array, checked = _check_call("ask_tell", method, x0, options)
    budget_or_default = checked.get("budget", 1000 * x0_array.size)
    if chosen == "adaptive":
        raw = _native._AskTell.adaptive(x0_array, _adaptive_options(checked))
        return AskTell(raw, "adaptive", budget_or_default)
    if chosen == "polished":
        raw = _native._AskTell.adaptive(x0_array, _polished_options(checked))
        return AskTell(raw, "polished", budget_or_default)
    o = _PaperOptions.given(checked)
    # The estimator's own checks, with its messages (it is never evaluated).
    PlateauFreeGradient(
        lambda x: 0.0,
        samples=o.samples,
        sampling=o.sampling,
        antithetic=o.antithetic,
        orthogonal=o.orthogonal,
    )
    iterations, annealer, adam = o.schedule(checked.get("budget"), o.samples, checked.get("bounds"))
    raw = _native._AskTell.paper(
        x0_array,
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
    )
    return AskTell(raw, "plateau", budget_or_default)
