""":func:`minimize`: the adaptive search and the polish on the Rust ``plateau_free::Minimizer``,
the paper's loop and its baselines on the Rust ``Optimizer``."""

from __future__ import annotations

import functools
import json
import math
import os
from typing import Any, Callable, Literal, Optional, Union

import numpy as np
import numpy.typing as npt

from . import _native
from ._native import Annealer, FiniteDifference, PlateauFreeGradient, Spsa
from ._options import _adaptive_options, _check_call, _PaperOptions, _polished_options, _show
from ._result import OptimizeResult, _adaptive_result, _paper_result, _wants_intermediate_result
from ._types import _Bounds, _FloatArray, _SamplingName, _ScheduleName

_Method = Literal["adaptive", "plateau", "paper", "polished", "fd", "spsa"]


def minimize(
    fun: Callable[..., Any],
    x0: npt.ArrayLike,
    *,
    method: Optional[_Method] = "adaptive",
    budget: Optional[int] = None,
    seed: int = 0,
    sigma0: Optional[float] = None,
    bounds: Optional[_Bounds] = None,
    batched: bool = False,
    seeded: bool = False,
    callback: Optional[Callable[..., Any]] = None,
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
    annealer: Union[_ScheduleName, Annealer, None] = None,
    sigma_min: Optional[float] = None,
    step: Optional[float] = None,
    orthogonal: Optional[bool] = None,
    parallel: Optional[bool] = None,
    record_x: Optional[bool] = None,
    keep_history: Optional[int] = None,
    final_evaluation: Optional[bool] = None,
    checkpoint: Optional[Union[str, os.PathLike[str]]] = None,
    checkpoint_every: Optional[int] = None,
) -> OptimizeResult:
    """Minimise ``fun`` from ``x0``: ``minimize(fun, x0)`` is the first thing to try.

    ``method`` chooses the run, never the options given:

    - ``'adaptive'`` (the default) is the library's general-purpose search,
      ``plateau_free::minimize`` / ``plateau_free::Minimizer``: a Gaussian search distribution
      around a mean, ranked values, a spread and metric that adapt to ``fun`` (and grow on
      plateaus), restarts from the best point with a doubled population; no step size or
      learning rate to choose. It spends at most ``budget`` evaluations (default
      ``1000 * x0.size``) and returns the best point seen.
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
        ``fun(x) -> float`` with ``x`` a float64 array shaped like ``x0``; with
        ``seeded=True``, ``fun(x, seed)``; with ``batched=True``, ``fun(X) -> N values`` for
        ``X`` of shape ``(N, *x0.shape)`` (``(N, n)`` for a vector), and
        ``fun(X, seeds)`` when also seeded (``seeds``: ``uint64`` array of length ``N``).
    x0 : array_like
        The start: an array of finite numbers, at least one, inside ``bounds``.
    method : str
        ``'adaptive'`` (default; None means it too), ``'plateau'``/``'paper'``, ``'polished'``,
        ``'fd'`` or ``'spsa'``.
    budget : int, optional
        The most evaluations of ``fun`` the run spends, its final evaluation included:
        ``nfev <= budget`` always. Adaptive: default ``1000 * x0.size``. Polished: required.
        The paper's loop: when ``iterations`` is not given, as many iterations as the budget
        pays for, ``(budget - 1) // samples`` (``(budget - 1) // 2n`` for ``'fd'``, ``// 2``
        for ``'spsa'``; ``budget // ...`` with ``final_evaluation=False``); a budget that
        cannot pay for one iteration (and the final evaluation), or fewer than the
        ``iterations`` given need, is a ValueError.
    seed : int
        The seed of every random choice, from 0 to 2**64 - 1: the result is a function of
        ``fun``, ``x0``, the options and the seed alone (bit for bit the Rust side's).
    sigma0 : float, optional
        The initial spread. Adaptive: default a quarter of the mean box width with ``bounds``,
        else ``max(1, max|x0|) / 2``; it adapts from there. The paper's loop and polished:
        default 0.5 (the paper recommends about half the parameter domain).
    bounds : optional
        Box bounds: a sequence of ``(lower, upper)`` pairs, one per coordinate (``None`` for no
        bound), one ``(lower, upper)`` pair for all coordinates, or a
        ``scipy.optimize.Bounds``; ``x0`` must lie inside. Adaptive and polished: finite
        bounds, every evaluated point is projected onto the box. The paper's loop: Adam
        projects after every step.
    batched, seeded : bool
        The form of ``fun`` (see above). Adaptive: a batched ``fun`` is called once per
        iteration with the iteration's whole population; a seeded one gets the same seed for
        every point of an iteration (common random numbers), a new one each iteration.
    callback : callable, optional
        Called after every iteration, as in scipy: ``callback(intermediate_result)`` when its
        only parameter is named ``intermediate_result``, else ``callback(x)``. Returning a
        true value (``True``, ``1``, ``np.True_``) or raising ``StopIteration`` stops the run
        (``status`` 99, ``success`` False); the result is then the best point so far
        (adaptive, polished) or the current iterate (the paper's loop). The paper's loop
        passes an :class:`OptimizeResult` with ``x``, ``fun`` -- the iteration's mean value
        --, ``nit``, ``nfev``, ``sigma``, ``jac`` -- the gradient estimate; adaptive: ``x``
        and ``fun`` the best point and value so far, with ``nit`` and ``nfev``.
    target : float, optional
        Adaptive, polished: stop as soon as ``fun`` reaches ``target`` or below.
    population : int, optional
        Adaptive, polished: the population of the first run (default ``4 + floor(3 ln n)``, at
        least 2); each restart doubles it.
    restarts : bool, optional
        Adaptive, polished: restart from the best point with a doubled population when a run
        converges or stalls while budget remains (default True). False: the run ends with
        ``'converged'``.
    polish : float, optional
        Polished: the fraction of ``budget``, in ``[0, 1)``, that the adaptive search gets
        after the paper's loop (default 0.25; 0: the loop alone, its best point returned).
    stop_when_stalled : float, optional
        Adaptive, polished (``Minimizer::stop_when_stalled``): end the run once the best value
        has not improved at all over the last ``stop_when_stalled * budget`` evaluations
        (rounded up), a fraction in ``(0, 1]``; :data:`STALL_WINDOW` (0.2) is the tested
        choice. Judged after every generation of the adaptive search (polished: from the
        hand-over, the paper's loop runs its whole share); the result then has status 0 and
        a message saying it stalled. Default None: off, the budget alone ends the run. Not an
        option of the paper's loop (``'plateau'``).
    iterations : int, optional
        The paper's loop: iterations to run; default the annealer's length if ``annealer`` is
        an :class:`Annealer`, else as many as ``budget`` pays for, else 400.
    lr : float, optional
        Adam's learning rate (the paper's loop and polished; default 0.02).
    samples, sampling, antithetic, orthogonal, parallel
        As for :class:`PlateauFreeGradient` (the paper's loop; polished takes ``samples``,
        default 2).
    annealer : str or Annealer, optional
        The paper's loop: ``'paper'`` (default: sigma0 for half the run, then linear to
        ``sigma_min``), ``'constant'``, ``'exponential'``, ``'cosine'``, or an
        :class:`Annealer` (then ``sigma0`` and ``sigma_min`` are its own).
    sigma_min : float, optional
        The final spread of the decaying schedules (the paper's 0.01).
    step : float, optional
        ``'fd'`` alone: the finite difference's step (default 1e-3).
    record_x : bool, optional
        The paper's loop: keep ``x`` after every iteration in ``history.x`` (default False).
    keep_history : int, optional
        The paper's loop: how many of the last iterations ``history`` keeps (default a
        million: 32 bytes an iteration, ``8 n`` more with ``record_x``, so that a run of any
        length has bounded memory; at least 1). ``history.dropped`` counts the others.
    final_evaluation : bool, optional
        The paper's loop: evaluate ``fun`` once at the final ``x`` for ``result.fun`` (default
        True; it counts in ``nfev`` and ``budget``). False: ``result.fun`` is the last
        iteration's mean value.
    checkpoint : str or path, optional
        The paper's loop: a file that keeps the run's state (theta, Adam's moments, the
        iteration, the random streams' position, the history so far) and what the run is:
        the method, ``x0``, its shape, the options and seed, and ``fun``'s name
        (``module.qualname``). Written atomically every ``checkpoint_every`` iterations, at
        the end, and when ``fun`` or ``callback`` raises (``KeyboardInterrupt`` included). If
        the file exists, the run continues from it and the result is bit for bit that of the
        run never interrupted; ``result.from_checkpoint`` is True and ``result.message`` names
        the file (``'restored from the finished checkpoint PATH: ...'`` when nothing was left
        to run). A file of another run (another ``fun``, ``x0``, option...), or a damaged one,
        is a ValueError naming the path and the difference, and is not used.
    checkpoint_every : int, optional
        Iterations between checkpoints; 0: only at the end and on an exception (default:
        about every 30 seconds, from the measured time per iteration).

    Returns
    -------
    OptimizeResult
        ``x``, ``fun``, ``nit``, ``nfev``, ``success``, ``status``, ``message``, ``history``;
        adaptive and polished: also ``restarts`` and ``sigma`` (``history`` is None); the
        paper's loop: also ``from_checkpoint``. ``success`` and ``status`` as scipy's:

        ============================================  =========  ======
        how the run ended                             success    status
        ============================================  =========  ======
        ``target`` reached; converged (no restarts)   True       0
        stalled (``stop_when_stalled``)               True       0
        budget spent (adaptive, polished)             False      1
        all iterations done (the paper's loop)        False      1
        the callback returned a true value or raised  False      99
        ``StopIteration``
        ============================================  =========  ======

    Raises
    ------
    ValueError
        A bad option, naming it and showing its value: of the wrong type (then an
        :class:`OptionTypeError`, also a TypeError), out of range, or not an option of the
        method; a non-finite or empty ``x0``, ``x0`` outside the bounds; ``fun`` returning NaN
        or an infinity, or a batch of the wrong length.
    TypeError
        ``fun`` returning something that is not a number.
    Exception
        Whatever ``fun`` or ``callback`` raises (but ``StopIteration`` from the callback),
        unchanged (KeyboardInterrupt included: Ctrl-C stops the run within one call of
        ``fun``).
    """
    options = dict(
        budget=budget, seed=seed, sigma0=sigma0, bounds=bounds, batched=batched, seeded=seeded,
        callback=callback, target=target, population=population, restarts=restarts,
        polish=polish, stop_when_stalled=stop_when_stalled, iterations=iterations, lr=lr,
        samples=samples, sampling=sampling,
        antithetic=antithetic, annealer=annealer, sigma_min=sigma_min, step=step,
        orthogonal=orthogonal, parallel=parallel, record_x=record_x, keep_history=keep_history,
        final_evaluation=final_evaluation, checkpoint=checkpoint,
        checkpoint_every=checkpoint_every,
    )  # fmt: skip
    if not callable(fun):
        raise _native.OptionTypeError(f"fun = {_show(fun)} must be callable")
    chosen, x0_array, checked = _check_call("minimize", method, x0, options)
    if chosen in ("adaptive", "polished"):
        return _minimize_adaptive(fun, x0_array, chosen, checked)
    return _minimize_paper(fun, x0_array, chosen, checked)


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


def _minimize_adaptive(
    fun: Callable[..., Any], x0: np.ndarray, method: str, checked: dict[str, Any]
) -> OptimizeResult:
    """``method='adaptive'`` and ``'polished'``: the Rust ``plateau_free::Minimizer``."""
    options = _polished_options(checked) if method == "polished" else _adaptive_options(checked)
    callback = _Callback(checked["callback"]) if "callback" in checked else None
    raw = _native._minimize_adaptive(
        fun,
        x0,
        options,
        batched=checked["batched"],
        seeded=checked["seeded"],
        callback=None if callback is None else callback.adaptive,
    )
    budget = checked.get("budget", 1000 * x0.size)
    return _adaptive_result(raw, budget, None if callback is None else callback.stop)


def _minimize_paper(
    fun: Callable[..., Any], x0: np.ndarray, method: str, checked: dict[str, Any]
) -> OptimizeResult:
    """The paper's loop (``method='plateau'``) and its baselines (``'fd'``, ``'spsa'``) on the
    Rust ``Optimizer``, then the final evaluation."""
    o = _PaperOptions.given(checked)
    estimator, per_iteration = _estimator(fun, method, o, checked, x0.size)
    budget, box = checked.get("budget"), checked.get("bounds")
    iterations, annealer, adam = o.schedule(budget, per_iteration, box)
    path = checked.get("checkpoint")
    settings = None
    if path is not None:
        settings = _checkpoint_settings(fun, x0, method, o, checked, iterations, annealer)
    callback = _Callback(checked["callback"]) if "callback" in checked else None
    raw = _native._minimize(
        estimator,
        x0,
        adam,
        annealer,
        iterations=iterations,
        callback=None if callback is None else callback.paper,
        record_x=o.record_x,
        checkpoint=path,
        checkpoint_every=checked.get("checkpoint_every"),
        settings=settings,
        keep_history=o.keep_history,
    )
    final = None
    if o.final_evaluation:
        form = dict(batched=checked["batched"], seeded=checked["seeded"], seed=checked["seed"])
        final = _evaluate(fun, raw["x"], **form)
    return _paper_result(raw, final, None if callback is None else callback.stop, path)


def _estimator(
    fun: Callable[..., Any], method: str, o: _PaperOptions, checked: dict[str, Any], n: int
) -> tuple[Any, int]:
    """The gradient estimator of the paper's loop (or of a baseline) and its evaluations per
    iteration."""
    common = dict(seed=checked["seed"], batched=checked["batched"], seeded=checked["seeded"])
    if method == "fd":
        return FiniteDifference(fun, step=o.step, **common), 2 * n
    if method == "spsa":
        return Spsa(fun, **common), 2
    estimator = PlateauFreeGradient(
        fun,
        samples=o.samples,
        sampling=o.sampling,
        antithetic=o.antithetic,
        orthogonal=o.orthogonal,
        parallel=o.parallel,
        **common,
    )
    return estimator, o.samples


def _checkpoint_settings(
    fun: Callable[..., Any],
    x0: np.ndarray,
    method: str,
    o: _PaperOptions,
    checked: dict[str, Any],
    iterations: int,
    annealer: Annealer,
) -> str:
    """What a run continued from a checkpoint must share with the run that wrote it, as JSON:
    compared key by key, in alphabetical order, by the Rust side."""
    return json.dumps(
        _jsonable(
            {
                "fun": _identity(fun),
                "method": method,
                "x0": x0.ravel().tolist(),
                "shape": list(x0.shape),
                "samples": o.samples,
                "sampling": o.sampling,
                "antithetic": o.antithetic,
                "orthogonal": o.orthogonal,
                "seed": checked["seed"],
                "lr": o.lr,
                "schedule": repr(annealer),
                "sigma0": o.sigma0,
                "sigma_min": o.sigma_min,
                "iterations": iterations,
                "step": o.step,
                "batched": checked["batched"],
                "seeded": checked["seeded"],
                "record_x": o.record_x,
                "bounds": checked.get("bounds"),
            }
        )
    )


def _identity(fun: Any) -> str:
    """``fun``'s name as best Python can tell, the same from one process to the next:
    ``module.qualname`` of a function or method, of a callable object's class, of a partial's
    function."""
    if isinstance(fun, functools.partial):
        return f"functools.partial({_identity(fun.func)})"
    named = fun if hasattr(fun, "__qualname__") else type(fun)
    module = getattr(named, "__module__", None) or "?"
    return f"{module}.{getattr(named, '__qualname__', type(fun).__qualname__)}"


def _evaluate(
    fun: Callable[..., Any], x: np.ndarray, *, batched: bool, seeded: bool, seed: int
) -> float:
    """``fun(x)`` in whichever form ``fun`` takes; a NaN or an infinity is refused as the
    estimator refuses one, naming the point (``result.fun`` is never silently non-finite)."""
    if batched:
        points = x[np.newaxis].copy()
        values = fun(points, np.array([seed], dtype=np.uint64)) if seeded else fun(points)
        value = _one_of_batch(values)
    else:
        value = _real_value(fun(x.copy(), seed) if seeded else fun(x.copy()))
    if not math.isfinite(value):
        raise ValueError(
            f"fun returned {value!r} at the final x = {np.array2string(x, threshold=8)}: "
            "the final evaluation must be finite"
        )
    return value


def _not_real(value: Any) -> TypeError:
    return TypeError(
        f"fun must return a real number, it returned {type(value).__name__}: {_show(value)}"
    )


def _real_value(value: Any) -> float:
    """``fun``'s value as a float, by the rules of the Rust side's evaluations
    (``to_f64`` in python/src/objective.rs): a real number -- Python's, numpy's, a 0-d array,
    anything with ``__float__`` --; TypeError for anything else (None, a string, a complex
    number, an array of several values, an int too large for a float)."""
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


def _one_of_batch(values: Any) -> float:
    """The one value a batched ``fun`` returned for a batch of one point, by the rules of
    ``read_values`` in python/src/objective.rs: one real number in a sequence or a 1-d array;
    TypeError for what is not real numbers, ValueError for another count."""
    must = f"batched fun must return 1 real number (one per row of its argument), it returned {_show(values)}"
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
    if array.shape not in ((1,), ()):  # a scalar too, as numpy.ascontiguousarray reads it
        raise ValueError(
            "batched fun must return 1 value (one per row of its argument), it returned an "
            f"array of shape {list(array.shape)}"
        )
    return float(array.reshape(-1)[0])


def _jsonable(value: Any) -> Any:
    """``value`` with tuples as lists and non-finite floats as their repr, for JSON."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    return value
