"""Usable gradients for black-box, plateau-ridden and discontinuous functions.

``plateau_free`` smooths an objective ``f: R^n -> R`` with a Gaussian in parameter space,

    Q_sigma(x) = E_{tau ~ N(0, sigma^2 I)} f(x + tau),

and estimates ``grad Q_sigma`` by importance-sampled, antithetic Monte Carlo from values of
``f`` alone (Fischer and Ritschel, "Plateau-reduced Differentiable Path Tracing", CVPR 2023).
The smoothed objective has no plateaus; an annealed ``sigma`` and Adam do the rest. The methods
run in Rust; :func:`minimize` asks them for points and evaluates ``fun`` on them in Python (on
``workers`` when given), and a failed evaluation, Ctrl-C, progress and checkpoints are handled
the same way for every method.

The main entry points:

- :class:`PlateauFreeGradient` -- ``PlateauFreeGradient(fun).estimate(x, sigma)``.
- :func:`minimize` -- ``minimize(fun, x0)`` runs the library's general-purpose search
  (``plateau_free::Minimizer``, ``method='adaptive'``, at most ``budget`` evaluations, default
  ``1000 * x0.size``); ``method='plateau'``, the paper's loop; ``method='polished'``, the
  paper's loop and then the adaptive search. Returns an :class:`OptimizeResult`.
- :class:`Annealer` (``paper``, ``constant``, ``exponential``, ``cosine``), :class:`Adam`
  (with bounds), :class:`Sampling` (``Radial``, ``PerCoordinate``, ``Gaussian``).
- :func:`ask_tell` -- the same runs with the points evaluated by the caller:
  ``es = ask_tell(x0)``, then ``X, seeds = es.ask()`` and ``es.tell(values)``
  until ``es.done``; ``es.result`` is :func:`minimize`'s result.
- :func:`least_squares` -- for a ``fun`` that returns an array (a residual image): the
  Gaussian-smoothed Jacobian on a sparsity pattern and damped Gauss-Newton steps, on
  :func:`minimize`'s run (failures, Ctrl-C, callback, progress, history, checkpoint, workers).
- :class:`FiniteDifference`, :class:`Spsa` -- the baselines (also in ``plateau_free.baseline``).
- :func:`plot_history` -- a run's history as a figure (matplotlib, the ``[plot]`` extra).
- :class:`OptionTypeError` -- an option of the wrong type: a ValueError (as every bad option)
  and a TypeError.

Submodules imported on demand, each with its extra: ``plateau_free.ray`` (``[ray]``),
``plateau_free.nevergrad`` (``[nevergrad]``: registers ``PlateauFree`` in nevergrad's
optimizers), ``plateau_free.drjit`` (``[mitsuba]``: ``PlateauFreeOp``, our gradient inside
Dr.Jit's, for Mitsuba 3). See ``docs/integrations.md``.

The estimators, :class:`Adam` and :class:`AskTell` may be shared by threads: their calls are
serialised, one at a time per object, in the order the threads get its lock.
"""

from __future__ import annotations

from ._ask_tell import AskTell, ask_tell
from ._least_squares import least_squares
from ._minimize import minimize
from ._native import (
    PAPER_SIGMA_MIN,
    PAPER_WARMUP,
    STALL_WINDOW,
    Adam,
    Annealer,
    FiniteDifference,
    OptionTypeError,
    PlateauFreeGradient,
    Spsa,
    __version__,
)
from ._plot import plot_history
from ._result import History, OptimizeResult, SearchHistory
from ._types import Sampling

__all__ = [
    "PAPER_SIGMA_MIN",
    "PAPER_WARMUP",
    "STALL_WINDOW",
    "Adam",
    "Annealer",
    "AskTell",
    "FiniteDifference",
    "History",
    "OptimizeResult",
    "OptionTypeError",
    "PlateauFreeGradient",
    "Sampling",
    "SearchHistory",
    "Spsa",
    "ask_tell",
    "least_squares",
    "minimize",
    "plot_history",
]

# The public names live in the private modules below (one job each: _types, _result,
# _options, _minimize, _ask_tell); they are shown, and pickled, as ``plateau_free``'s own.
for _public in (
    AskTell, History, OptimizeResult, Sampling, SearchHistory, ask_tell, least_squares, minimize,
    plot_history,
):  # fmt: skip
    _public.__module__ = __name__
del _public
