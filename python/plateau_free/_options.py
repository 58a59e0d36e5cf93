"""The options of :func:`plateau_free.minimize` and :func:`plateau_free.ask_tell`, declared once:
:data:`_OPTIONS` holds each option's check, the methods that take it, whether :func:`ask_tell`
takes it too, and its documentation (both functions' docstrings are made from it);
:class:`Options` holds its type. A row's check converts the value to what the run takes and
raises :class:`OptionTypeError` for a wrong type; the ranges of the library's options are
the library's checks (``Options::check`` and the builders), made when the run is built,
before any evaluation, their errors naming the Python keyword (``python/src/objective.rs``'s
``value_error``). Only the options the library does not have (``workers``, ``checkpoint``,
...) have their ranges checked here. Adding an option of the adaptive search is a row in
:data:`_OPTIONS`, a key in :class:`Options` and in :func:`_adaptive_options`, and a field in
``python/src/convert.rs``'s ``AdaptiveOptions``: two files.

Here too: the check of a whole call (the method, the options it takes, ``x0``, the bounds,
the combinations), and the options in the forms the runs take."""

from __future__ import annotations

import dataclasses
import difflib
import functools
import inspect
import os
from typing import TYPE_CHECKING, Any, Callable, NamedTuple, Optional, Sequence, TypedDict, TypeVar, Union, cast

import numpy as np
import numpy.typing as npt

from . import _native
from ._checks import (
    _annealer,
    _arguments,
    _box,
    _callable,
    _count,
    _counter,
    _flag,
    _metric,
    _number,
    _path,
    _policy,
    _sampling,
    _seed,
    _show,
    _spread,
    _start,
    _whole,
    _workers,
)
from ._native import DEFAULT_POLISH as _DEFAULT_POLISH
from ._native import PAPER_SIGMA_MIN, Adam, Annealer
from ._types import _Bounds, _SamplingName, _ScheduleName

if TYPE_CHECKING:
    from concurrent.futures import Executor


class Options(TypedDict, total=False):
    """The types of the options of :func:`minimize` and :func:`ask_tell` (documented in
    :data:`_OPTIONS`, which checks their types)."""

    budget: Optional[int]
    seed: Optional[int]
    sigma0: Union[float, Sequence[float], None]
    bounds: Optional[_Bounds]
    integrality: Any
    args: Any
    batched: bool
    seeded: bool
    callback: Optional[Callable[..., Any]]
    on_failure: str
    workers: Union[int, Executor, Callable[..., Any], None]
    disp: Optional[bool]
    checkpoint: Union[str, os.PathLike[str], None]
    checkpoint_every: Optional[int]
    keep_history: Optional[int]
    target: Optional[float]
    population: Optional[int]
    metric: Optional[str]
    restarts: Optional[bool]
    patience: Optional[int]
    polish: Optional[float]
    stop_when_stalled: Optional[float]
    iterations: Optional[int]
    lr: Optional[float]
    samples: Optional[int]
    sampling: Optional[_SamplingName]
    antithetic: Optional[bool]
    annealer: Union[_ScheduleName, Annealer, None]
    sigma_min: Optional[float]
    step: Optional[float]
    orthogonal: Optional[bool]
    parallel: Optional[bool]
    record_x: Optional[bool]
    final_evaluation: Optional[bool]


class _Option(NamedTuple):
    """One option: its check (name, value) -> the value the run uses; the methods that take
    it; whether :func:`ask_tell` takes it (else it is :func:`minimize`'s alone); its type and
    documentation as the docstrings show them."""

    check: Callable[[str, Any], Any]
    methods: frozenset[str]
    ask_tell: bool
    kind: str
    doc: str


_ALL = frozenset({"adaptive", "polished", "plateau", "fd", "spsa"})
_SEARCH = frozenset({"adaptive", "polished"})  # the Rust Minimizer's runs
_LOOP = frozenset({"plateau", "fd", "spsa"})  # the paper's loop and its baselines
_POLICY = frozenset({"adaptive", "polished", "plateau"})  # the runs with a failure policy


def _row(check: Callable[[str, Any], Any], methods: frozenset[str], kind: str, doc: str,
         ask_tell: bool = True) -> _Option:  # fmt: skip
    return _Option(check, methods, ask_tell, kind, doc)


_OPTIONS: dict[str, _Option] = {
    "budget": _row(_count(" of evaluations"), _ALL, "int, optional", """
        The most evaluations of ``fun`` the run spends, its final evaluation included:
        ``nfev <= budget`` always. Adaptive: default ``1000 * x0.size``. Polished: required.
        The paper's loop: when ``iterations`` is not given, as many iterations as the budget
        pays for, ``(budget - 1) // samples`` (``(budget - 1) // 2n`` for ``'fd'``, ``// 2``
        for ``'spsa'``; ``budget // ...`` with ``final_evaluation=False``); a budget that
        cannot pay for one iteration (and the final evaluation), or fewer than the
        ``iterations`` given need, is a ValueError."""),
    "seed": _row(_seed, _ALL, "int or None", """
        The seed of every random choice, from 0 to 2**64 - 1 (default 0): the result is a
        function of ``fun``, ``x0``, the options and the seed alone (bit for bit the Rust
        side's). None: a fresh seed from the operating system. ``result.seed`` records the
        seed used, to run the same again."""),
    "sigma0": _row(_spread, frozenset({"adaptive", "polished", "plateau", "spsa"}),
                   "float or sequence of floats, optional", """
        The initial spread. Adaptive: default a quarter of the mean box width with finite
        ``bounds``, else ``max(1, max|x0|) / 2``; a sequence gives one spread per coordinate
        (parameters of different scales); it adapts from there. The paper's loop and
        polished: one number, default 0.5 (the paper recommends about half the parameter
        domain)."""),
    "bounds": _row(lambda name, value: value, _ALL, "optional", """
        Box bounds: a sequence of ``(lower, upper)`` pairs, one per coordinate, one pair for
        all coordinates, or a ``scipy.optimize.Bounds``; ``None`` or an infinity leaves that
        side open (``(None, 2)``); ``x0`` must lie inside. Adaptive and polished: every
        evaluated point is projected onto the box (its integer coordinates folded into it:
        docs/integers.md). The paper's loop: Adam projects after
        every step."""),
    "integrality": _row(lambda name, value: _integrality(name, value), frozenset({"adaptive"}),
                        "array of 0 and 1, optional", """
        Adaptive: which coordinates are integers, scipy's convention (``integrality`` of
        ``scipy.optimize.milp`` and ``differential_evolution``): 1 an integer, 0 continuous,
        one per coordinate of ``x0`` (flattened) or one for all. Every point handed to ``fun``,
        ``x0`` included, and ``result.x`` have those coordinates rounded to integers inside
        ``bounds`` (which must hold an integer on each); the spread along them keeps a floor,
        and a selected draw that rounded to another integer than the mean's is learnt from at
        that integer (``Minimizer::steps``, docs/integers.md)."""),
    "args": _row(_arguments, _ALL, "tuple, optional", """
        Extra arguments of ``fun``, as scipy's: ``fun(x, *args)`` (``fun(x, seed, *args)``
        when seeded).""", ask_tell=False),
    "batched": _row(_flag, _ALL, "bool", """
        ``fun(X) -> N values`` for ``X`` of shape ``(N, *x0.shape)``, called once per
        iteration with its whole population (default False).""", ask_tell=False),
    "seeded": _row(_flag, _ALL, "bool", """
        ``fun(x, seed)`` (``fun(X, seeds)`` when also batched, ``seeds`` a uint64 array):
        adaptive gives every point of an iteration the same seed (common random numbers), a
        new one each iteration (default False).""", ask_tell=False),
    "callback": _row(_callable, _ALL, "callable, optional", """
        Called after every iteration, as in scipy: ``callback(intermediate_result)`` when its
        only parameter is named ``intermediate_result``, else ``callback(x)``. Returning a
        true value or raising ``StopIteration`` stops the run (``status`` 99); the result is
        then the best point so far (adaptive, polished) or the current iterate (the paper's
        loop). The paper's loop passes ``x``, ``fun`` (the iteration's mean value), ``nit``,
        ``nfev``, ``sigma`` and ``jac`` (the gradient estimate); adaptive the best ``x`` and
        ``fun`` so far, with ``nit`` and ``nfev``.""", ask_tell=False),
    "on_failure": _row(_policy, _POLICY, "'continue' or 'raise'", """
        What a failed evaluation does: NaN, an infinity, or an exception raised by ``fun``
        (an ``Exception``; Ctrl-C is not a failure). ``'continue'`` (default): the point
        ranks below every finite value (the paper's loop redraws the estimate), the run goes
        on and ``result.nfail`` counts it; a run whose every evaluation raised raises the
        first exception. ``'raise'``: the run ends with the exception (a ValueError for NaN
        or an infinity) and ``exc.result`` holds the result so far, its best point
        included. Not an option of the baselines (``'fd'``, ``'spsa'``), which end on the
        first failure."""),
    "workers": _row(_workers, _ALL, "int, Executor or callable, optional", """
        Where an iteration's points are evaluated: a number of threads, a
        ``concurrent.futures.Executor`` (its ``map``), or a map-like callable
        ``workers(function, points)`` (scipy's ``differential_evolution`` convention; a
        process pool needs ``fun`` to pickle). The result is bit for bit the run of one
        worker (default 1: in this thread).""", ask_tell=False),
    "disp": _row(_flag, _ALL, "bool, optional", """
        Print a plain progress line every few seconds and at the end, in the words of the
        library's ``ProgressLine`` (iteration, evaluations of the budget, best value, spread,
        time; failures when any; default False).""", ask_tell=False),
    "checkpoint": _row(_path, _ALL, "str or path, optional", """
        A file that keeps the run's state and what the run is (the method, ``x0``, the
        options, the seed, ``fun``'s ``module.qualname``). Written atomically every
        ``checkpoint_every`` iterations (default about every 30 seconds), at the end, on
        Ctrl-C and when ``fun`` or ``callback`` raises. If the file exists, the run continues
        from it and ends bit for bit as the run never interrupted; ``result.from_checkpoint``
        is True and ``result.message`` names the file. A file of another run (another
        ``fun``, ``x0``, option...), or a damaged one, is a ValueError naming the path and the
        difference, and is not used.""", ask_tell=False),
    "checkpoint_every": _row(_counter(0, " of iterations"), _ALL, "int, optional", """
        Iterations between checkpoints; 0: only at the end, on Ctrl-C and on an exception
        (default: about every 30 seconds).""", ask_tell=False),
    "keep_history": _row(_counter(1, " of iterations"), _ALL, "int, optional", """
        How many iterations ``result.history`` keeps (default a million, so that a run of any
        length has bounded memory): the paper's loop, the last ones; adaptive and polished,
        between ``keep_history`` and twice as many spread evenly over the run, the last
        iteration's last. ``history.dropped`` counts the others."""),
    "target": _row(_number, _SEARCH, "float, optional", """
        Adaptive, polished: stop as soon as ``fun`` reaches ``target`` or below."""),
    "population": _row(_count(), _SEARCH, "int, optional", """
        Adaptive, polished: the population of the first run (default ``4 + floor(3 ln n)``,
        at least 2); each restart doubles it."""),
    "metric": _row(_metric, _SEARCH, "str, optional", """
        Adaptive, polished: the metric the search distribution learns (``Metric``):
        ``'auto'`` (default: ``'full'`` up to n = 19, ``'decoded'`` from 20 to 200,
        ``'diagonal'`` above), ``'full'`` (a
        covariance: rotated, ill-conditioned functions; ``O(n^2)`` per evaluation, refused
        above n = 10,000), ``'decoded'`` (the full covariance decoded by a diagonal one
        learned much faster, dd-CMA-ES: axis-parallel scales about as fast as ``'diagonal'``,
        rotated structure as ``'full'``; the full metric's cost and limit), ``'diagonal'``
        (one spread per coordinate, ``O(n)``) or
        ``'low_rank'`` (the diagonal times ``4 + 3 ln n`` directions of recent progress,
        LM-MA-ES's limited memory: rotated structure at ``O(n ln n)``; measured in
        docs/results/large-scale.md)."""),
    "restarts": _row(_flag, _SEARCH, "bool, optional", """
        Adaptive, polished: restart from the start (``x0``; the polish: the loop's best point),
        or from the best point once a run has found it again, with a doubled population when
        a run converges or stalls while budget remains (default True)."""),
    "patience": _row(_count(" of restarts"), _SEARCH, "int, optional", """
        Adaptive, polished: how many restarts in a row must converge back at the best point
        seen before them for the run to be done before its budget (status 0, ``success``
        True, the message says so); default 1 (``Minimizer::patience``); 0: the budget, the
        target or the stall rule alone end the run."""),
    "polish": _row(_number, frozenset({"polished"}), "float, optional", """
        Polished: the fraction of ``budget``, in ``[0, 1)``, that the adaptive search gets
        after the paper's loop (default 0.5, as the Rust ``Minimizer`` and the path tracer;
        0: the loop alone, its best point returned)."""),
    "stop_when_stalled": _row(_number, _SEARCH, "float, optional", """
        Adaptive, polished: end the run once the best value has not improved over the last
        ``stop_when_stalled * budget`` evaluations, a fraction in ``(0, 1]``
        (:data:`STALL_WINDOW` is the tested choice); status 0 with a message saying it
        stalled. Default None: off."""),
    "iterations": _row(_counter(1), _LOOP, "int, optional", """
        The paper's loop: iterations to run; default the annealer's length if ``annealer``
        is an :class:`Annealer`, else as many as ``budget`` pays for, else 400."""),
    "lr": _row(_number, _LOOP | {"polished"}, "float, optional", """
        Adam's learning rate (the paper's loop and polished; default 0.02)."""),
    "samples": _row(_count(), frozenset({"plateau", "polished"}), "int, optional", """
        Evaluations per gradient estimate, as for :class:`PlateauFreeGradient` (default 2;
        even with antithetic pairs)."""),
    "sampling": _row(_sampling, frozenset({"plateau"}), "str, optional", """
        The sampler, as for :class:`PlateauFreeGradient` (default ``'radial'``)."""),
    "antithetic": _row(_flag, frozenset({"plateau"}), "bool, optional", """
        Antithetic pairs, as for :class:`PlateauFreeGradient` (default True)."""),
    "orthogonal": _row(_flag, frozenset({"plateau"}), "bool, optional", """
        Orthogonal directions, as for :class:`PlateauFreeGradient` (default False)."""),
    "parallel": _row(_flag, frozenset({"plateau"}), "bool, optional", """
        Evaluate an estimate's points on threads (as ``workers=os.cpu_count()``; default
        False).""", ask_tell=False),
    "annealer": _row(_annealer, frozenset({"plateau", "spsa"}), "str or Annealer, optional", """
        The paper's loop: ``'paper'`` (default: sigma0 for half the run, then linear to
        ``sigma_min``), ``'constant'``, ``'exponential'``, ``'cosine'``, or an
        :class:`Annealer` (then ``sigma0`` and ``sigma_min`` are its own)."""),
    "sigma_min": _row(_number, frozenset({"plateau", "spsa"}), "float, optional", """
        The final spread of the decaying schedules (the paper's 0.01)."""),
    "step": _row(_number, frozenset({"fd"}), "float, optional", """
        ``'fd'`` alone: the finite difference's step (default 1e-3).""", ask_tell=False),
    "record_x": _row(_flag, _LOOP, "bool, optional", """
        The paper's loop: keep ``x`` after every iteration in ``history.x`` (default
        False)."""),
    "final_evaluation": _row(_flag, _LOOP, "bool, optional", """
        The paper's loop: evaluate ``fun`` once at the final ``x`` for ``result.fun`` (default
        True; it counts in ``nfev`` and ``budget``). False: ``result.fun`` is the last
        iteration's mean value."""),
}  # fmt: skip

# The options whose None is a bad value, not "not given" (seed: None is fresh entropy).
_ALWAYS_CHECKED = ("seed", "batched", "seeded")

# Names users bring from other libraries, and the word to use here.
_SAY_INSTEAD = {
    "maxiter": "budget= (evaluations of fun; iterations= for the paper's loop)",
    "maxfev": "budget= (evaluations of fun)",
    "maxfun": "budget= (evaluations of fun)",
    "max_evals": "budget= (evaluations of fun)",
    "tol": "target= (a value to stop at) or stop_when_stalled= (a window of the budget)",
    "ftol": "target= (a value to stop at) or stop_when_stalled= (a window of the budget)",
    "xtol": "target= (a value to stop at) or stop_when_stalled= (a window of the budget)",
    "fatol": "target= (a value to stop at) or stop_when_stalled= (a window of the budget)",
    "options": "each option as a keyword of its own: minimize(fun, x0, budget=..., seed=...)",
    "rng": "seed=",
    "random_state": "seed=",
    "verbose": "disp=",
    "x0": "the second positional argument",
}


def _refuse_unknown(where: str, options: dict[str, Any], known: Optional[Sequence[str]] = None) -> None:
    """A TypeError naming each keyword that is no option (of ``known``, default every option
    of :func:`minimize`), and the word to use instead."""
    names = list(_OPTIONS) if known is None else list(known)
    for name in options:
        if name in names:
            continue
        hint = _SAY_INSTEAD.get(name)
        word = (hint or "").split(" ")[0]
        if word.endswith("=") and word[:-1] not in names:
            hint = None  # the word to use is not a keyword of this function
        if hint is None:
            close = difflib.get_close_matches(name, names, n=1)
            hint = f"{close[0]}=" if close else "one of " + ", ".join(sorted(names))
        raise TypeError(f"{where}() got an unexpected keyword argument {name!r}: use {hint}")


_F = TypeVar("_F", bound=Callable[..., Any])


def _says_instead(function: _F) -> _F:
    """``function`` with :func:`_refuse_unknown`'s TypeError for a keyword it does not take
    (``maxiter=``: "use budget="), its signature unchanged for type checkers."""
    parameters = inspect.signature(function).parameters
    keywords = [n for n, p in parameters.items() if p.kind is not inspect.Parameter.POSITIONAL_ONLY]

    @functools.wraps(function)
    def checked(*args: Any, **kwargs: Any) -> Any:
        _refuse_unknown(function.__name__, {k: v for k, v in kwargs.items() if k not in parameters},
                        keywords)  # fmt: skip
        return function(*args, **kwargs)

    return cast(_F, checked)


def _owners(name: str) -> str:
    methods = [f"'{m}'" for m in _METHODS if m in _OPTIONS[name].methods]
    return methods[0] if len(methods) == 1 else ", ".join(methods[:-1]) + " or " + methods[-1]


_METHODS = ("adaptive", "plateau", "polished", "fd", "spsa")


def _takes(method: str, where: str) -> set[str]:
    """The options ``method`` takes in ``where`` (``'minimize'`` or ``'ask_tell'``)."""
    return {
        name
        for name, option in _OPTIONS.items()
        if method in option.methods and (where == "minimize" or option.ask_tell)
    }


def _options_doc(where: str, indent: str = "    ") -> str:
    """The Parameters entries of every option of ``where``, for its docstring."""
    lines = []
    for name, option in _OPTIONS.items():
        if where == "ask_tell" and not option.ask_tell:
            continue
        lines.append(f"{indent}{name} : {option.kind}")
        body = [line.strip() for line in option.doc.strip().splitlines()]
        lines.extend(f"{indent}    {line}" for line in body)
    return "\n".join(lines)


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
        raise _native.OptionTypeError(f"method = {_show(method)} is not a method: use {names}")
    chosen = {"paper": "plateau"}.get(method.lower(), method.lower())
    if chosen not in _METHODS or (where == "ask_tell" and chosen in ("fd", "spsa")):
        raise ValueError(f"method = {_show(method)} is not a method of {where}: use {names}")
    return chosen


def _refuse_foreign(method: str, given: dict[str, Any], where: str) -> None:
    """A ValueError naming every option given that ``method`` does not take, with its value."""
    takes = _takes(method, where)
    foreign = [name for name in given if name not in takes]
    if foreign:
        raise ValueError("; ".join(_foreign(name, given[name], method, where) for name in foreign))


def _foreign(name: str, value: Any, method: str, where: str) -> str:
    """Why ``method`` in ``where`` does not take option ``name``: another method's option, or
    one of ``minimize`` alone (it drives the run, which the caller of ask and tell does)."""
    if method in _OPTIONS[name].methods:
        return (f"{name} = {_show(value)}: not an option of ask_tell, an option of minimize "
                "(with ask and tell the caller runs the evaluations)")
    default = " (the default method)" if method == "adaptive" else ""
    return (f"{name} = {_show(value)}: not an option of method={method!r}{default}, "
            f"an option of method={_owners(name)}")


def _check_call(
    where: str, method: Any, x0: Any, options: dict[str, Any]
) -> tuple[str, np.ndarray, dict[str, Any]]:
    """The method, ``x0`` and the options of a :func:`minimize` (``where='minimize'``) or
    :func:`ask_tell` call, checked: keywords that are no option (a TypeError naming the word
    to use), the options given (not None) that the method does not take, then each option's
    type and range, ``x0``, the bounds, the combinations. Returns the options given, each in
    the form the run uses, with ``seed``, ``batched``, ``seeded`` and ``on_failure`` always
    there."""
    _refuse_unknown(where, options)
    chosen = _method(method, where)
    given = {k: v for k, v in options.items() if v is not None or k in _ALWAYS_CHECKED}
    _refuse_foreign(chosen, given, where)
    checked = {n: _OPTIONS[n].check(n, value) for n, value in given.items() if n != "bounds"}
    checked = {"seed": 0, "batched": False, "seeded": False, "on_failure": "continue", **checked}
    start = _start(x0)
    if "bounds" in given:
        checked["bounds"] = _box(given["bounds"], start, x0)
    if "integrality" in checked:
        checked["integrality"] = _integral_steps(checked["integrality"], start.size, options)
    spread = checked.get("sigma0")
    if isinstance(spread, list):
        if chosen != "adaptive":
            raise ValueError(
                f"sigma0 = {_show(options['sigma0'])}: method={chosen!r} takes one number "
                "(one spread per coordinate is method='adaptive''s)"
            )
        if len(spread) != start.size:
            raise ValueError(
                f"sigma0 has {len(spread)} spreads, x0 has {start.size} coordinates: give one "
                "number or one per coordinate"
            )
    if checked["batched"] and checked.get("workers", 1) != 1:
        raise ValueError(
            f"workers = {_show(options['workers'])}: a batched fun evaluates its batch itself; "
            "give batched=False to spread the points over workers"
        )
    if chosen == "polished" and "budget" not in checked:
        raise ValueError(
            "budget: method='polished' needs one (the paper's loop spends the first "
            "1 - polish of it, the adaptive search the rest)"
        )
    if 0 < checked.get("budget", 1000 * start.size) < checked.get("population", 0):
        # A generation is drawn whole (its points held in memory) before the budget cuts it;
        # a budget of 0 is the library's error.
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
    spread = None if paper is not None else checked.get("sigma0")
    return {
        "budget": checked.get("budget"),
        "seed": checked.get("seed", 0),
        "sigma0": spread if not isinstance(spread, list) else None,
        "sigma0_each": spread if isinstance(spread, list) else None,
        "bounds": checked.get("bounds"),
        "target": checked.get("target"),
        "population": checked.get("population"),
        "metric": checked.get("metric", "auto"),
        "restarts": checked.get("restarts", True),
        "paper": paper,
        "polish": polish,
        "stall": checked.get("stop_when_stalled"),
        "on_failure": checked.get("on_failure", "continue"),
        "patience": checked.get("patience"),
        "steps": checked.get("integrality"),
    }


def _integrality(name: str, value: Any) -> npt.NDArray[np.bool_]:
    """``integrality``: a 0 or 1 (or bool) for each coordinate or one for all."""
    must = f"{name} = {_show(value)} must be 0 or 1 (or booleans) per coordinate, scipy's integrality"
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise _native.OptionTypeError(must) from e
    if array.dtype.kind not in "biuf" or array.ndim > 1:
        raise _native.OptionTypeError(must)
    if not np.all((array == 0) | (array == 1)):
        raise ValueError(must)
    return array.astype(bool)


def _integral_steps(flags: npt.NDArray[np.bool_], size: int, options: dict[str, Any]) -> list[float]:
    """The steps of ``integrality`` for ``size`` coordinates: 1.0 an integer, 0.0 continuous."""
    if flags.ndim == 1 and flags.size != size:
        raise ValueError(
            f"integrality = {_show(options['integrality'])} has {flags.size} entries, x0 has "
            f"{size} coordinates: give one per coordinate or one for all"
        )
    return [1.0 if f else 0.0 for f in np.broadcast_to(flags, (size,))]


def _polished_options(checked: dict[str, Any]) -> _native._AdaptiveOptions:
    """``method='polished'``: the paper loop's ``(samples, lr, sigma0)`` (the paper loop's
    defaults) and the polish fraction (default half the budget), with the adaptive search's options."""
    defaults = _PaperOptions()
    paper = (
        int(checked.get("samples", defaults.samples)),
        float(checked.get("lr", defaults.lr)),
        float(checked.get("sigma0", defaults.sigma0)),
    )
    return _adaptive_options(checked, paper, float(checked.get("polish", _DEFAULT_POLISH)))


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
