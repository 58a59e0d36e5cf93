"""What a :func:`minimize` run's checkpoint (``checkpoint=path``) must match to be resumed: its
settings (``fun``'s name, the method, ``x0`` and its shape, the options given), by name. The
file itself is the library's (``lifecycle::Checkpoint``), compared in this order, sorted by
name."""

from __future__ import annotations

import functools
import json
import math
from typing import Any, Callable

import numpy as np


def _identity(fun: Any) -> str:
    """``fun``'s name as best Python can tell, the same from one process to the next:
    ``module.qualname`` of a function or method, of a callable object's class, of a partial's
    function."""
    if isinstance(fun, functools.partial):
        return f"functools.partial({_identity(fun.func)})"
    named = fun if hasattr(fun, "__qualname__") else type(fun)
    module = getattr(named, "__module__", None) or "?"
    return f"{module}.{getattr(named, '__qualname__', type(fun).__qualname__)}"


def _jsonable(value: Any) -> Any:
    """``value`` with tuples as lists, numpy values as Python's and non-finite floats as their
    repr, for JSON."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    return repr(value)


def _compact(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"))


# The options that do not change what a run computes: left out of the settings a resumed run
# must share.
_NOT_IDENTITY = ("callback", "checkpoint", "checkpoint_every", "disp", "workers", "args")


def _settings(
    fun: Callable[..., Any],
    x0: np.ndarray,
    method: str,
    checked: dict[str, Any],
    extra: dict[str, Any],
) -> dict[str, Any]:
    """What a run continued from a checkpoint must share with the run that wrote it: ``fun``'s
    name, the method, ``x0`` and its shape, the options given and ``extra`` (the paper loop's
    iterations and schedule)."""
    settings = {k: v for k, v in checked.items() if k not in _NOT_IDENTITY}
    settings.setdefault("bounds", None)
    settings.update(
        fun=_identity(fun), method=method, x0=x0.ravel().tolist(), shape=list(x0.shape), **extra
    )
    return settings


def _setting_pairs(settings: dict[str, Any]) -> list[tuple[str, str]]:
    """``settings`` as the checkpoint's identity: ``(name, compact JSON)``, sorted by name."""
    jsonable = _jsonable(settings)
    return [(key, _compact(jsonable[key])) for key in sorted(jsonable)]
