"""Evaluating ``fun`` on the points a run asks for: in this thread, on threads, on an executor or
through a map-like callable, in the order of the points (so that the run is bit for bit the run
of one worker); a NaN, an infinity or an exception is a failure, counted, and under
``on_failure='raise'`` the end of the run. ``fun`` gives one value a point (:func:`minimize`)
or a vector of outputs (:func:`least_squares`: a point with any non-finite output failed)."""

from __future__ import annotations

import math
from concurrent.futures import Executor, ThreadPoolExecutor
from typing import Any, Callable, Optional

import numpy as np
import numpy.typing as npt

from ._checks import _show
from ._types import _FloatArray


class _Raised:
    """An exception raised by ``fun`` on a worker, carried back to the run as a value."""

    __slots__ = ("error",)

    def __init__(self, error: Exception) -> None:
        self.error = error


class _Call:
    """``fun`` at one ``(x, seed)``: its value, or the exception it raised as a :class:`_Raised`
    (an ``Exception``: Ctrl-C and ``SystemExit`` pass). Picklable when ``fun`` and ``args``
    are, for a process pool."""

    def __init__(self, fun: Callable[..., Any], args: tuple[Any, ...], seeded: bool) -> None:
        self.fun = fun
        self.args = args
        self.seeded = seeded

    def __call__(self, item: tuple[_FloatArray, int]) -> Any:
        x, seed = item
        try:
            if self.seeded:
                return self.fun(x, seed, *self.args)
            return self.fun(x, *self.args)
        except Exception as e:
            return _Raised(e)


def _not_real(value: Any) -> TypeError:
    return TypeError(
        f"fun must return a real number, it returned {type(value).__name__}: {_show(value)}"
    )


def _real_value(value: Any) -> float:
    """``fun``'s value as a float: a real number -- Python's, numpy's, a 0-d array, anything
    with ``__float__`` --; TypeError for anything else (None, a string, a complex number, an
    array of several values, an int too large for a float)."""
    if isinstance(value, float):
        return float(value)
    if isinstance(value, (str, bytes, bytearray, complex, np.complexfloating)) or (
        isinstance(value, np.ndarray) and value.dtype.kind == "c"
    ):
        raise _not_real(value)
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError) as e:
        raise _not_real(value) from e


def _batch_values(values: Any, count: int) -> _FloatArray:
    """The ``count`` values a batched ``fun`` returned: real numbers in a sequence or a 1-d
    array; TypeError for what is not real numbers, ValueError for another count."""
    if (
        isinstance(values, np.ndarray)
        and values.dtype == np.float64
        and values.shape == (count,)
    ):
        return values  # the usual case, taken as it is
    must = (
        f"batched fun must return {count} real numbers (one per row of its argument), it "
        f"returned {_show(values)}"
    )
    if values is None or isinstance(values, (str, bytes, bytearray)):
        raise TypeError(must)
    try:
        array = np.asarray(values)
    except ValueError as e:  # a ragged nesting
        raise ValueError(f"{must}: {e}") from e
    if array.dtype.kind not in "biufO":
        raise TypeError(must)
    try:
        array = array.astype(np.float64)
    except (TypeError, ValueError, OverflowError) as e:
        raise TypeError(f"{must}: {e}") from e
    if array.shape != (count,) and not (count == 1 and array.shape == ()):
        raise ValueError(
            f"batched fun must return {count} values (one per row of its argument), it "
            f"returned an array of shape {list(array.shape)}"
        )
    return array.reshape(-1)


class _Evaluator:
    """``fun`` on a run's points, as :func:`minimize`'s options say: ``args``, ``batched``,
    ``seeded``, ``workers`` and ``on_failure``. Counts the failures (:attr:`failures`) and
    keeps the first exception (:attr:`first_error`, and its repr :attr:`first_error_text`,
    which a checkpoint keeps). With ``outputs`` (:func:`least_squares`), ``fun`` returns that
    many outputs a point (0: as many as at the first point), given back flat."""

    def __init__(
        self,
        fun: Callable[..., Any],
        *,
        args: tuple[Any, ...] = (),
        batched: bool = False,
        seeded: bool = False,
        workers: Any = 1,
        on_failure: str = "continue",
        outputs: Optional[int] = None,
    ) -> None:
        self.fun = fun
        self.args = args
        self.batched = batched
        self.call = _Call(fun, args, seeded)
        self.raise_failures = on_failure == "raise"
        self.outputs = outputs
        self.failures = 0
        self.exceptions = 0
        self.first_error: Optional[Exception] = None
        self.first_error_text: Optional[str] = None
        self._pool: Optional[ThreadPoolExecutor] = None
        self._map: Optional[Callable[..., Any]] = None
        if isinstance(workers, int) and workers > 1:
            self._pool = ThreadPoolExecutor(workers, thread_name_prefix="plateau_free")
            self._map = self._pool.map
        elif isinstance(workers, Executor) or (
            hasattr(workers, "submit") and callable(getattr(workers, "map", None))
        ):
            self._map = workers.map
        elif callable(workers):
            self._map = workers

    def close(self) -> None:
        """Ends the threads of ``workers=k`` (the points in flight are dropped)."""
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None

    def __call__(self, points: _FloatArray, seeds: npt.NDArray[np.uint64]) -> _FloatArray:
        """The values at ``points`` (one row each) with their ``seeds``: NaN where ``fun``
        raised (under ``'continue'``)."""
        if self.outputs is not None:
            return self._rows(points, seeds)
        if self.batched:
            values = self._batch(points, seeds)
        else:
            items = [(points[k].copy(), int(seeds[k])) for k in range(len(points))]
            raw = map(self.call, items) if self._map is None else self._map(self.call, items)
            values = np.array([self._value(v) for v in raw], dtype=np.float64)
        self.failures += int(np.count_nonzero(~np.isfinite(values)))
        return values

    def _rows(self, points: _FloatArray, seeds: npt.NDArray[np.uint64]) -> _FloatArray:
        """A vector ``fun``'s outputs at ``points``, flat: a row of NaN where it raised."""
        items = [(points[k].copy(), int(seeds[k])) for k in range(len(points))]
        raw = map(self.call, items) if self._map is None else self._map(self.call, items)
        rows = [self._row(v) for v in raw]
        self.failures += sum(1 for row in rows if not np.isfinite(row).all())
        return np.concatenate(rows) if rows else np.zeros(0)

    def _row(self, value: Any) -> _FloatArray:
        """One point's outputs, as many as at the first point."""
        if isinstance(value, _Raised):
            if not self.outputs:
                raise value.error  # the first point's outputs give their count: none to fill
            self._raised(value.error)
            return np.full(self.outputs, math.nan)
        try:
            row = np.asarray(value, dtype=np.float64).ravel()
        except (TypeError, ValueError) as e:
            raise TypeError(f"fun must return an array of real numbers, it returned {_show(value)}") from e
        if row.size == 0:
            raise ValueError("fun returned an empty array: it must return at least one value")
        if not self.outputs:
            self.outputs = row.size
        elif row.size != self.outputs:
            raise ValueError(
                f"fun returned {row.size} values at this point, {self.outputs} at x0: the count must not change"
            )
        return row

    def _batch(self, points: _FloatArray, seeds: npt.NDArray[np.uint64]) -> _FloatArray:
        batch = points.copy()
        try:
            if self.call.seeded:
                raw = self.fun(batch, seeds.copy(), *self.args)
            else:
                raw = self.fun(batch, *self.args)
        except Exception as e:
            self._raised(e, len(points))
            return np.full(len(points), math.nan)
        return _batch_values(raw, len(points))

    def _value(self, value: Any) -> float:
        if isinstance(value, _Raised):
            self._raised(value.error)
            return math.nan
        return _real_value(value)

    def _raised(self, error: Exception, points: int = 1) -> None:
        """``fun`` raised ``error`` on ``points`` points: raised again under ``'raise'``, else
        counted (the first kept)."""
        if self.raise_failures:
            raise error
        self.exceptions += points
        if self.first_error is None:
            self.first_error = error
            self.first_error_text = repr(error)
