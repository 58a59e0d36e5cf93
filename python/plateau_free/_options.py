"""The options of :func:`plateau_free.minimize` and :func:`plateau_free.ask_tell`, checked and with
their defaults filled in: the method and the options it takes, every option's type and range
(each error names the option and shows its value as given), ``x0``, the bounds, the adaptive
search's and the paper loop's options."""

from __future__ import annotations

import dataclasses
import math
import os
import sys
from typing import Any, Callable, Optional, Union, cast

import numpy as np

from . import _native
from ._native import PAPER_SIGMA_MIN, Adam, Annealer, OptionTypeError
from ._types import _ScheduleName

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


def _whole(name: str, value: Any, lowest: int, highest: int = _USIZE_MAX, what: str = "") -> int:
    """``value`` as an int in ``[lowest, highest]``: an int (numpy's included) or a float with a
    whole value (``1e4``); OptionTypeError for a non-number, ValueError for another number."""
    must = f"{name} = {_show(value)} must be a whole number{what} from {lowest} to {_limit(highest)}"
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


def _positive(name: str, value: Any) -> float:
    must = f"{name} = {_show(value)} must be a finite number > 0"
    if not _is_real(value):
        raise OptionTypeError(must)
    number = _as_float(value, must)
    if not (math.isfinite(number) and number > 0):
        raise ValueError(must)
    return number


def _fraction(name: str, value: Any) -> float:
    must = (
        f"{name} = {_show(value)} must be a fraction of the budget in [0, 1) "
        "(the share the adaptive search gets after the paper's loop)"
    )
    if not _is_real(value):
        raise OptionTypeError(must)
    if not 0.0 <= value < 1.0:
        raise ValueError(must)
    return float(value)


def _window(name: str, value: Any) -> float:
    """``stop_when_stalled``: a fraction of the budget in ``(0, 1]`` (NaN fails the test)."""
    must = (
        f"{name} = {_show(value)} must be a fraction of the budget in (0, 1] (the window over "
        "which the best value must improve; plateau_free.STALL_WINDOW = 0.2 is the tested choice)"
    )
    if not _is_real(value):
        raise OptionTypeError(must)
    if not 0.0 < value <= 1.0:
        raise ValueError(must)
    return float(value)


def _not_nan(name: str, value: Any) -> float:
    must = f"{name} = {_show(value)} must be a number (not NaN)"
    if not _is_real(value):
        raise OptionTypeError(must)
    number = _as_float(value, must)
    if math.isnan(number):
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
    return lambda name, value: _whole(name, value, lowest, what=what)


# Every option's check (bounds aside: it needs x0); each returns the value in the form the run
# uses.
_CHECKS: dict[str, Callable[[str, Any], Any]] = {
    "budget": _counter(1, " of evaluations"),
    "seed": lambda name, value: _whole(name, value, 0, _U64_MAX),
    "sigma0": _positive,
    "lr": _positive,
    "sigma_min": _positive,
    "step": _positive,
    "iterations": _counter(1),
    "samples": _counter(1),
    "population": _counter(2),
    "checkpoint_every": _counter(0, " of iterations"),
    "keep_history": _counter(1, " of iterations"),
    "target": _not_nan,
    "polish": _fraction,
    "stop_when_stalled": _window,
    "sampling": _sampling,
    "annealer": _annealer,
    "callback": _callable,
    "checkpoint": _path,
    **{
        flag: _flag
        for flag in ("antithetic", "orthogonal", "parallel", "record_x", "final_evaluation",
                     "restarts", "batched", "seeded")
    },
}  # fmt: skip

# The options with a default other than None: None given for them is a bad value, not "not
# given".
_ALWAYS_CHECKED = ("seed", "batched", "seeded")

# The options each method takes (besides fun, x0 and method).
_ADAPTIVE = {
    "budget", "seed", "sigma0", "bounds", "target", "population", "restarts", "batched", "seeded",
    "callback", "stop_when_stalled",
}  # fmt: skip
_LOOP = {
    "budget", "seed", "bounds", "batched", "seeded", "callback", "iterations", "lr", "record_x",
    "keep_history", "final_evaluation", "checkpoint", "checkpoint_every",
}  # fmt: skip
_SPSA = _LOOP | {"sigma0", "annealer", "sigma_min"}
_PLATEAU = _SPSA | {"samples", "sampling", "antithetic", "orthogonal", "parallel"}
_TAKES = {
    "adaptive": _ADAPTIVE,
    "plateau": _PLATEAU,
    "polished": _ADAPTIVE | {"lr", "samples", "polish"},
    "fd": _LOOP | {"step"},
    "spsa": _SPSA,
}
_ASK_TELL_LEAVES = {"batched", "seeded", "callback", "parallel", "checkpoint", "checkpoint_every"}


def _method(method: Any, where: str) -> str:
    """The method's canonical name (``'paper'`` is ``'plateau'``; None is the default,
    ``'adaptive'``)."""
    names = "'adaptive', 'plateau', 'polished', 'fd' or 'spsa'"
    if where == "ask_tell":
        names = (
            "'adaptive', 'plateau' or 'polished' (the baselines 'fd' and 'spsa' are minimize's alone)"
        )
    if method is None:
        return "adaptive"
    if not isinstance(method, str):
        raise OptionTypeError(f"method = {_show(method)} is not a method: use {names}")
    chosen = {"paper": "plateau"}.get(method.lower(), method.lower())
    if chosen not in _TAKES or (where == "ask_tell" and chosen in ("fd", "spsa")):
        raise ValueError(f"method = {_show(method)} is not a method of {where}: use {names}")
    return chosen


def _owners(name: str) -> str:
    methods = [f"'{m}'" for m, takes in _TAKES.items() if name in takes]
    return methods[0] if len(methods) == 1 else ", ".join(methods[:-1]) + " or " + methods[-1]


def _refuse_foreign(method: str, given: dict[str, Any], where: str) -> None:
    """A ValueError naming every option given that ``method`` does not take, with its value."""
    takes = _TAKES[method] - (_ASK_TELL_LEAVES if where == "ask_tell" else set())
    foreign = [name for name in given if name not in takes]
    if foreign:
        default = " (the default method)" if method == "adaptive" else ""
        raise ValueError(
            "; ".join(
                f"{name} = {_show(given[name])}: not an option of method={method!r}{default}, "
                f"an option of method={_owners(name)}"
                for name in foreign
            )
        )


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


def _box(bounds: Any, x0: np.ndarray, given: Any, method: str) -> tuple[list[float], list[float]]:
    """``(lower, upper)`` lists of ``x0.size`` numbers from scipy-style bounds; ``x0`` (``given``
    as the user wrote it) must lie inside; finite bounds for the adaptive search."""
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
        if method in ("adaptive", "polished") and not (math.isfinite(lo) and math.isfinite(hi)):
            raise ValueError(
                f"bounds[{i}] = {_show(items[i])}: method={method!r} needs finite bounds "
                "(the box sets the starting spread and where restarts go)"
            )
        if not lo <= v <= hi:
            raise ValueError(
                f"x0[{i}] = {_show(start[i])} is outside bounds[{i}] = {_show(items[i])}"
            )
    return [p[0] for p in pairs], [p[1] for p in pairs]


def _check_call(
    where: str, method: Any, x0: Any, options: dict[str, Any]
) -> tuple[str, np.ndarray, dict[str, Any]]:
    """The method, ``x0`` and the options of a :func:`minimize` (``where='minimize'``) or
    :func:`ask_tell` call, checked: the options given (not None) that the method does not
    take, then each option's type and range, ``x0``, the bounds. Returns the options given,
    each in the form the run uses."""
    chosen = _method(method, where)
    given = {k: v for k, v in options.items() if v is not None or k in _ALWAYS_CHECKED}
    _refuse_foreign(chosen, given, where)
    checked = {n: _CHECKS[n](n, value) for n, value in given.items() if n != "bounds"}
    start = _start(x0)
    if "bounds" in given:
        checked["bounds"] = _box(given["bounds"], start, x0, chosen)
    if chosen == "polished" and "budget" not in checked:
        raise ValueError(
            "budget: method='polished' needs one (the paper's loop spends the first "
            "1 - polish of it, the adaptive search the rest)"
        )
    if checked.get("population", 0) > checked.get("budget", 1000 * start.size):
        # A generation is drawn whole (its points held in memory) before the budget cuts it.
        budget = checked.get("budget")
        spelt = f"budget = {budget}" if budget is not None else f"the default budget, {1000 * start.size}"
        raise ValueError(
            f"population = {_show(options['population'])} is more than {spelt} evaluations: "
            "a generation must fit in the budget; give a smaller population or a larger budget"
        )
    if chosen in ("plateau", "polished"):
        _check_pairs(chosen, checked)
    if isinstance(checked.get("annealer"), Annealer):
        for name in ("sigma0", "sigma_min"):
            if name in checked:
                raise ValueError(
                    f"{name} = {_show(options[name])}: the Annealer given as annealer has its own "
                    f"({getattr(checked['annealer'], name)}); give one or the other"
                )
    return chosen, start, checked


def _check_pairs(method: str, checked: dict[str, Any]) -> None:
    """Antithetic pairs (always, for method='polished') need an even number of samples."""
    samples = checked.get("samples", 2)
    if checked.get("antithetic", True) and samples % 2:
        remedy = "" if method == "polished" else " or antithetic=False"
        raise ValueError(
            f"samples = {samples}: antithetic pairs need an even number of samples; "
            f"use an even count{remedy}"
        )


def _adaptive_options(
    checked: dict[str, Any],
    paper: Optional[tuple[int, float, float]] = None,
    polish: Optional[float] = None,
) -> _native._AdaptiveOptions:
    """The options of ``method='adaptive'`` (and, with ``paper`` and ``polish``, of
    ``method='polished'``) as the Rust side takes them, the same for :func:`minimize` and
    :func:`ask_tell`."""
    return {
        "budget": checked.get("budget"),
        "seed": checked.get("seed", 0),
        "sigma0": None if paper is not None else checked.get("sigma0"),
        "bounds": checked.get("bounds"),
        "target": checked.get("target"),
        "population": checked.get("population"),
        "restarts": checked.get("restarts", True),
        "paper": paper,
        "polish": polish,
        "stall": checked.get("stop_when_stalled"),
    }


def _polished_options(checked: dict[str, Any]) -> _native._AdaptiveOptions:
    """``method='polished'``: the paper loop's ``(samples, lr, sigma0)`` (the paper loop's
    defaults) and the polish fraction (default a quarter), with the adaptive search's options."""
    defaults = _PaperOptions()
    paper = (
        int(checked.get("samples", defaults.samples)),
        float(checked.get("lr", defaults.lr)),
        float(checked.get("sigma0", defaults.sigma0)),
    )
    return _adaptive_options(checked, paper, float(checked.get("polish", 0.25)))


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
    keep_history: Optional[int] = None
    final_evaluation: bool = True
    iterations: Optional[int] = None

    @classmethod
    def given(cls, checked: dict[str, Any]) -> _PaperOptions:
        """The options given, the defaults for the rest."""
        fields = {f.name for f in dataclasses.fields(cls)}
        return cls(**{name: value for name, value in checked.items() if name in fields})

    def schedule(
        self, budget: Optional[int], per_iteration: int, box: Any
    ) -> tuple[int, Annealer, Adam]:
        """The number of iterations (given, the annealer's, as many as ``budget`` pays for
        with the final evaluation, or 400), the annealer and Adam (with the box)."""
        final = int(self.final_evaluation)
        iterations, annealer = self.iterations, self.annealer
        if iterations is None and isinstance(annealer, Annealer):
            iterations = annealer.iterations
        if iterations is None and budget is not None:
            iterations = (budget - final) // per_iteration
            if iterations < 1:
                also = " and the final evaluation" if final else ""
                raise ValueError(
                    f"budget = {budget} cannot pay for one iteration ({per_iteration} evaluations)"
                    f"{also}: give a budget of at least {per_iteration + final}"
                    + (" or final_evaluation=False" if final else "")
                )
        iterations = 400 if iterations is None else iterations
        if budget is not None and iterations * per_iteration + final > budget:
            raise ValueError(
                f"iterations = {iterations} of {per_iteration} evaluations"
                + (" and the final evaluation" if final else "")
                + f" need {iterations * per_iteration + final}, more than budget = {budget}"
            )
        if not isinstance(annealer, Annealer):
            schedule = cast(_ScheduleName, annealer)
            annealer = Annealer(
                schedule, sigma0=self.sigma0, sigma_min=self.sigma_min, iterations=iterations
            )
        return iterations, annealer, Adam(self.lr, bounds=box)
