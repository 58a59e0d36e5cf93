"""The checks of single option values for :mod:`plateau_free._options`: each takes the option's
name and its value as given, returns the value in the form the run uses, and raises an
:class:`OptionTypeError` for a value of the wrong type, naming the option and showing its value
as written. The range of an option the library has is the library's check (:func:`_number`,
:func:`_count`); here, a ValueError for a value out of range of an option that Python alone has
(``workers``, ``checkpoint_every``, ...). Also ``x0`` and the bounds."""

from __future__ import annotations

import math
import os
import sys
from typing import Any, Callable, Union, cast

import numpy as np

from ._native import Annealer, OptionTypeError

_USIZE_MAX = sys.maxsize * 2 + 1  # the largest count the Rust side takes (usize)
_U64_MAX = 2**64 - 1


def _show(value: Any) -> str:
    """``value`` as the user wrote it: its repr (a numpy scalar as the Python number it holds),
    cut to 80 characters."""
    if isinstance(value, np.generic):
        value = value.item()
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _limit(highest: int) -> str:
    return "2**64 - 1" if highest == _U64_MAX else str(highest)


def _is_bool(value: Any) -> bool:
    return isinstance(value, (bool, np.bool_))


def _is_real(value: Any) -> bool:
    """Whether ``value`` is a real number (an int or a float, numpy's included; not a bool)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not _is_bool(value)


def _whole(name: str, value: Any, lowest: int, highest: int = _USIZE_MAX, what: str = "",
           must: str = "") -> int:  # fmt: skip
    """``value`` as an int in ``[lowest, highest]``: an int (numpy's included) or a float with a
    whole value (``1e4``); OptionTypeError for a non-number, ValueError for another number
    (``must``: the message, default the range)."""
    must = f"{name} = {_show(value)} " + (
        must or f"must be a whole number{what} from {lowest} to {_limit(highest)}"
    )
    if not _is_real(value):
        raise OptionTypeError(must)
    if isinstance(value, (float, np.floating)):
        if not (math.isfinite(value) and float(value).is_integer()):
            raise ValueError(must)
    number = int(value)
    if not lowest <= number <= highest:
        raise ValueError(must)
    return number


def _as_float(value: Any, must: str) -> float:
    """A real number (see :func:`_is_real`) as a float: ValueError naming it when it is an int
    too large for a float (``10**400``), not Python's OverflowError."""
    try:
        return float(value)
    except OverflowError as e:
        raise ValueError(f"{must}: it is too large for a float") from e


def _number(name: str, value: Any) -> float:
    """A real number option of the library (its range is the library's check): a float, or
    OptionTypeError."""
    must = f"{name} = {_show(value)} must be a number"
    if not _is_real(value):
        raise OptionTypeError(must)
    return _as_float(value, must)


def _positive(name: str, value: Any) -> float:
    """A spread of the Python adapters, which check it before the library sees it."""
    must = f"{name} = {_show(value)} must be a finite number > 0"
    if not _is_real(value):
        raise OptionTypeError(must)
    number = _as_float(value, must)
    if not (math.isfinite(number) and number > 0):
        raise ValueError(must)
    return number


def _flag(name: str, value: Any) -> bool:
    if not _is_bool(value):
        raise OptionTypeError(f"{name} = {_show(value)} must be True or False")
    return bool(value)


def _callable(name: str, value: Any) -> Callable[..., Any]:
    if not callable(value):
        raise OptionTypeError(f"{name} = {_show(value)} must be callable")
    return cast(Callable[..., Any], value)


def _path(name: str, value: Any) -> str:
    if not isinstance(value, (str, os.PathLike)):
        raise OptionTypeError(f"{name} = {_show(value)} must be a path (a str or an os.PathLike)")
    return os.fspath(value)


_SAMPLERS = ("radial", "per_coordinate", "gaussian")
_SCHEDULES = ("paper", "constant", "exponential", "cosine")


def _sampling(name: str, value: Any) -> str:
    must = f"{name} = {_show(value)} is not a sampler: use 'radial', 'per_coordinate' or 'gaussian'"
    if not isinstance(value, str):
        raise OptionTypeError(must)
    spelt = str(value).lower().replace("-", "_").replace(" ", "_")  # a Sampling's value
    spelt = "per_coordinate" if spelt == "percoordinate" else spelt
    if spelt not in _SAMPLERS:
        raise ValueError(must)
    return spelt


_METRICS = ("auto", "full", "decoded", "diagonal", "low_rank")


def _metric(name: str, value: Any) -> str:
    must = f"{name} = {_show(value)} is not a metric: use 'auto', 'full', 'decoded', 'diagonal' or 'low_rank'"
    if not isinstance(value, str):
        raise OptionTypeError(must)
    spelt = value.lower().replace("-", "_").replace(" ", "_")  # a Metric's value
    spelt = "low_rank" if spelt == "lowrank" else spelt
    if spelt not in _METRICS:
        raise ValueError(must)
    return spelt


def _annealer(name: str, value: Any) -> Union[str, Annealer]:
    must = (
        f"{name} = {_show(value)} is not a schedule: use 'paper', 'constant', 'exponential', "
        "'cosine' or an Annealer"
    )
    if isinstance(value, Annealer):
        return value
    if not isinstance(value, str):
        raise OptionTypeError(must)
    if value.lower() not in _SCHEDULES:
        raise ValueError(must)
    return value.lower()


def _counter(lowest: int, what: str = "") -> Callable[[str, Any], int]:
    """A count that Python alone takes (its range is checked here)."""
    return lambda name, value: _whole(name, value, lowest, what=what)


def _count(what: str = "") -> Callable[[str, Any], int]:
    """A count option of the library: a whole number the Rust side can take (a usize); its
    range is the library's check."""
    must = f"must be a whole number{what}, not negative and at most {_USIZE_MAX}"
    return lambda name, value: _whole(name, value, 0, what=what, must=must)


def _start(x0: Any) -> np.ndarray:
    """``x0`` as a float64 array: an array of finite numbers, at least one."""
    if x0 is None or isinstance(x0, (str, bytes)):
        raise OptionTypeError(f"x0 = {_show(x0)} must be an array of numbers (the start)")
    try:
        raw = np.asarray(x0)
        if raw.dtype.kind not in "biufO":
            raise TypeError(f"its elements are of dtype {raw.dtype}")
        array = np.asarray(raw, dtype=np.float64)
    except OverflowError as e:  # an int too large for a float: a number, but not a finite one
        raise ValueError(f"x0 = {_show(x0)} is not an array of finite numbers: {e}") from e
    except (TypeError, ValueError) as e:
        raise OptionTypeError(f"x0 = {_show(x0)} is not an array of numbers: {e}") from e
    if array.size == 0:
        raise ValueError(
            f"x0 = {_show(x0)} is empty (shape {array.shape}): the objective needs at least one parameter"
        )
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        index = np.unravel_index(int(bad[0]), array.shape)
        element = raw[index] if raw.ndim else raw.item()
        where = ", ".join(str(int(i)) for i in index)
        raise ValueError(f"x0[{where}] = {_show(element)} is not finite")
    return array


def _pair(i: int, pair: Any) -> tuple[float, float]:
    """``bounds[i]``: a ``(lower, upper)`` pair of numbers or None."""
    must = f"bounds[{i}] = {_show(pair)} must be a (lower, upper) pair of numbers or None"
    try:
        items = tuple(pair)
    except TypeError as e:
        raise OptionTypeError(must) from e
    if len(items) != 2 or not all(b is None or _is_real(b) for b in items):
        raise OptionTypeError(must)
    lower = -math.inf if items[0] is None else _as_float(items[0], must)
    upper = math.inf if items[1] is None else _as_float(items[1], must)
    if math.isnan(lower) or math.isnan(upper):
        raise ValueError(f"bounds[{i}] = {_show(pair)}: NaN is not a bound (None is no bound)")
    if lower > upper:
        raise ValueError(
            f"bounds[{i}] = {_show(pair)}: lower {_show(items[0])} > upper {_show(items[1])}"
        )
    return lower, upper


def _box(bounds: Any, x0: np.ndarray, given: Any) -> tuple[list[float], list[float]]:
    """``(lower, upper)`` lists of ``x0.size`` numbers from scipy-style bounds (None or an
    infinity: open on that side); ``x0`` (``given`` as the user wrote it) must lie inside."""
    n = x0.size
    if hasattr(bounds, "lb") and hasattr(bounds, "ub"):  # scipy.optimize.Bounds
        try:
            lb = np.broadcast_to(np.asarray(bounds.lb, dtype=float), x0.shape).ravel()
            ub = np.broadcast_to(np.asarray(bounds.ub, dtype=float), x0.shape).ravel()
        except (TypeError, ValueError, OverflowError) as e:
            raise ValueError(
                f"bounds = {_show(bounds)}: lb and ub must fit x0's shape {x0.shape}: {e}"
            ) from e
        items: list[Any] = list(zip(lb.tolist(), ub.tolist()))
    else:
        if isinstance(bounds, (str, bytes)) or not hasattr(bounds, "__iter__"):
            raise OptionTypeError(
                f"bounds = {_show(bounds)} must be (lower, upper) pairs, one per coordinate of x0, "
                "a single pair, or a scipy.optimize.Bounds"
            )
        items = list(bounds)
        if len(items) == 2 and all(b is None or np.ndim(b) == 0 for b in items):
            items = [tuple(items)]  # one (lower, upper) pair for every coordinate
        if len(items) == 1:
            items = items * n
        if len(items) != n:
            raise ValueError(
                f"bounds has {len(items)} (lower, upper) pairs, x0 has {n} coordinates: "
                "give one pair per coordinate or a single pair for all"
            )
    pairs = [_pair(i, b) for i, b in enumerate(items)]
    start = np.asarray(given, dtype=object).ravel()
    for i, ((lo, hi), v) in enumerate(zip(pairs, x0.ravel().tolist())):
        if not lo <= v <= hi:
            raise ValueError(
                f"x0[{i}] = {_show(start[i])} is outside bounds[{i}] = {_show(items[i])}"
            )
    return [p[0] for p in pairs], [p[1] for p in pairs]


def _seed(name: str, value: Any) -> int:
    """A seed from 0 to 2**64 - 1; None: fresh entropy from the operating system (the seed
    drawn is the one the result records)."""
    if value is None:
        return int(np.random.SeedSequence().generate_state(1, np.uint64)[0])
    return _whole(name, value, 0, _U64_MAX)


def _spread(name: str, value: Any) -> Union[float, list[float]]:
    """``sigma0``: a number, or a sequence of them (one per coordinate of ``x0``: the caller
    checks the length; the library checks each is finite and > 0)."""
    if isinstance(value, (str, bytes)) or value is None or np.ndim(value) == 0:
        return _number(name, value)
    must = f"{name} = {_show(value)} must be a number, or one per coordinate of x0"
    try:
        array = np.asarray(value)
        if array.dtype.kind not in "iuf":
            raise TypeError(f"its elements are of dtype {array.dtype}")
        spreads: list[float] = np.asarray(array, dtype=np.float64).ravel().tolist()
    except (TypeError, ValueError, OverflowError) as e:
        raise OptionTypeError(f"{must}: {e}") from e
    return spreads


_POLICIES = ("continue", "raise")


def _policy(name: str, value: Any) -> str:
    """``on_failure``: ``'continue'`` or ``'raise'``."""
    must = f"{name} = {_show(value)} is not a policy: use 'continue' or 'raise'"
    if not isinstance(value, str):
        raise OptionTypeError(must)
    if value.lower() not in _POLICIES:
        raise ValueError(must)
    return value.lower()


def _workers(name: str, value: Any) -> Any:
    """``workers``: a whole number of threads (at least 1), a ``concurrent.futures.Executor``,
    or a map-like callable ``workers(function, iterable)``."""
    if _is_real(value):
        return _whole(name, value, 1, what=" of threads")
    if hasattr(value, "submit") and callable(getattr(value, "map", None)):
        return value  # an Executor
    if callable(value):
        return value
    raise OptionTypeError(
        f"{name} = {_show(value)} must be a number of threads, a concurrent.futures.Executor "
        "or a map-like callable (such as an executor's map)"
    )


def _arguments(name: str, value: Any) -> tuple[Any, ...]:
    """``args``: the extra arguments of ``fun``, a tuple (a single non-tuple value is one
    argument, as scipy has it)."""
    return value if isinstance(value, tuple) else (value,)
