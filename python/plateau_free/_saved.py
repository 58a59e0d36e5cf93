"""The checkpoint file of a :func:`minimize` run (``checkpoint=path``): what the run is (its
settings, compared key by key on resume), its ask-and-tell state (the library's serde state),
the driver's progress and the points asked but not yet told; written atomically, read back
only whole and only for the same run."""

from __future__ import annotations

import functools
import hashlib
import json
import math
from typing import Any, Callable, Optional

import numpy as np

from . import _native

# The version of the file's layout.
_FORMAT = 2


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


def _checksum(payload: dict[str, Any]) -> str:
    return hashlib.sha256(_compact(payload).encode()).hexdigest()


class _Checkpoint:
    """Where a run keeps its checkpoint and with which settings; :meth:`load` reads it,
    :meth:`save` writes it."""

    def __init__(self, path: str, settings: dict[str, Any]) -> None:
        self.path = path
        self.settings = _jsonable(settings)

    def _damaged(self, why: str) -> ValueError:
        return ValueError(f"checkpoint {self.path} is damaged: {why}")

    def load(self) -> Optional[dict[str, Any]]:
        """The saved payload (``state``, ``progress``, ``pending``), or None without a file: a
        damaged file, or one of other settings, is a ValueError naming the path and the
        difference (never half-used)."""
        try:
            with open(self.path, "rb") as file:
                data = file.read()
        except FileNotFoundError:
            return None
        except OSError as e:
            raise ValueError(f"checkpoint {self.path} cannot be read: {e}") from e
        try:
            saved = json.loads(data)
            layout = saved["format"]
        except (ValueError, TypeError, KeyError) as e:
            raise self._damaged(f"not a checkpoint file ({e})") from e
        if layout != _FORMAT:
            raise ValueError(
                f"checkpoint {self.path} has format {layout}, this version reads {_FORMAT}"
            )
        if saved.get("version") != _native.__version__:
            raise ValueError(
                f"checkpoint {self.path} was written by plateau-free {saved.get('version')}, "
                f"this is {_native.__version__}"
            )
        found = saved.get("settings", {})
        for key in sorted(self.settings):
            old, here = found.get(key), self.settings[key]
            if old != here:
                raise ValueError(
                    f"checkpoint: {key} is {_compact(old)} in {self.path}, {_compact(here)} here"
                )
        payload = saved.get("payload")
        if not isinstance(payload, dict) or saved.get("checksum") != _checksum(payload):
            raise self._damaged("its contents do not match their checksum")
        return payload

    def save(self, payload: dict[str, Any]) -> None:
        """Replaces the file atomically (the library's ``replace_file``)."""
        text = _compact(
            {
                "format": _FORMAT,
                "version": _native.__version__,
                "settings": self.settings,
                "checksum": _checksum(payload),
                "payload": payload,
            }
        )
        _native._replace_file(self.path, text.encode())


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
