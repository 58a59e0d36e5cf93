"""``plateau_free.minimize`` as a method of ``scipy.optimize.minimize``.

    >>> import numpy as np, scipy.optimize, plateau_free.scipy
    >>> res = scipy.optimize.minimize(lambda x: float(np.sum(np.floor(x) ** 2)), [2.7, -1.4],
    ...                               method=plateau_free.scipy.method,
    ...                               options={"maxfev": 400, "seed": 1})
    >>> res.fun, res.nfev <= 400
    (0.0, True)

``options``: ``maxfev`` (scipy's name for the budget: ``minimize``'s ``budget``), ``seed``, and
every other option of :func:`plateau_free.minimize` by its own name (``method``, ``sigma0``,
``target``, ``samples``, ...; a wrong one is :func:`plateau_free.minimize`'s ValueError naming
it). scipy's ``args``, ``bounds`` (pairs or ``scipy.optimize.Bounds``) and ``callback`` (``callback(x)``
or ``callback(intermediate_result)``) are honoured; ``jac``, ``hess`` and ``hessp`` are not used
(a RuntimeWarning says so, as scipy's derivative-free methods do); ``constraints`` and ``tol``
are a ValueError, since the search cannot keep them. The result is a
``scipy.optimize.OptimizeResult`` with ``x``, ``fun``, ``nit``, ``nfev``, ``success``,
``status``, ``message`` and the fields of :class:`plateau_free.OptimizeResult`.

scipy is imported when ``method`` is first called: ``import plateau_free.scipy`` works without it.
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any, Callable, Optional, Sequence

from ._minimize import minimize
from ._options import _OPTIONS as _MINIMIZE_OPTIONS
from ._checks import _show


def method(
    fun: Callable[..., Any],
    x0: Any,
    args: Sequence[Any] = (),
    *,
    jac: Any = None,
    hess: Any = None,
    hessp: Any = None,
    bounds: Any = None,
    constraints: Any = (),
    callback: Optional[Callable[..., Any]] = None,
    maxfev: Optional[int] = None,
    **options: Any,
) -> Any:
    """Runs :func:`plateau_free.minimize` for ``scipy.optimize.minimize(fun, x0,
    method=plateau_free.scipy.method, options={...})``; ``maxfev`` is the budget. Returns a
    ``scipy.optimize.OptimizeResult``."""
    optimize = _import_scipy_optimize()
    for name, given in (("jac", jac), ("hess", hess), ("hessp", hessp)):
        if given is not None and given is not False:
            warnings.warn(
                f"plateau_free.scipy.method does not use derivatives ({name} = {_show(given)})",
                RuntimeWarning,
                stacklevel=3,
            )
    if constraints is not None and len(constraints) > 0:
        raise ValueError(
            f"constraints = {_show(constraints)}: plateau_free.scipy.method keeps box bounds alone (bounds=)"
        )
    if "tol" in options:
        raise ValueError(
            f"tol = {_show(options['tol'])}: plateau_free.scipy.method has no tolerance; "
            "give options={'maxfev': ...} or {'target': ...}"
        )
    if "budget" in options:
        raise ValueError(f"budget = {_show(options['budget'])}: give scipy's name, options={{'maxfev': ...}}")
    for name in options:
        if name not in _OPTIONS:
            raise ValueError(
                f"{name} = {_show(options[name])}: not an option of plateau_free.scipy.method "
                f"(it takes maxfev and {', '.join(sorted(_OPTIONS))})"
            )
    if tuple(args):
        options["args"] = tuple(args)
    result = minimize(fun, x0, budget=maxfev, bounds=bounds, callback=callback, **options)
    return optimize.OptimizeResult(dict(result))


# minimize's own options, but those that scipy.optimize.minimize gives by keyword.
_OPTIONS = frozenset(_MINIMIZE_OPTIONS) - {"budget", "bounds", "callback", "args"} | {"method"}


def _import_scipy_optimize() -> Any:
    try:
        return importlib.import_module("scipy.optimize")
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            'plateau_free.scipy needs scipy: pip install "plateau-free[scipy]" (or the pinned scipy of python/requirements-test.txt)'
        ) from e
