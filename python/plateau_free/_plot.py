""":func:`plot_history`: a run's history as a matplotlib figure (the ``[plot]`` extra)."""

from __future__ import annotations

import importlib
from typing import Any, Optional

import numpy as np

from ._result import History, OptimizeResult, SearchHistory


def plot_history(result: OptimizeResult, ax: Optional[Any] = None) -> Any:
    """Draws ``result.history`` against the evaluations spent: the best value so far and the
    spread (adaptive, polished: :class:`SearchHistory`), or the iterations' mean value and
    sigma (the paper's loop: :class:`History`), on a log scale where the values allow.

    Needs matplotlib (``pip install plateau-free[plot]``). Draws on ``ax`` (a matplotlib
    Axes) when given, else on a new figure; returns the Axes. The spread is on a second
    y-axis, the right one.

    Raises
    ------
    ValueError
        ``result`` has no history (``AskTell.result`` of the adaptive search).
    ImportError
        matplotlib is not installed, naming the extra that brings it.
    """
    history = result.get("history")
    if not isinstance(history, (History, SearchHistory)):
        raise ValueError("result has no history to plot (result.history is None)")
    try:
        # Imported by name: matplotlib is an optional extra, and typed or not as installed.
        plt: Any = importlib.import_module("matplotlib.pyplot")
    except ImportError as e:
        raise ImportError(
            "plot_history needs matplotlib: pip install plateau-free[plot]"
        ) from e
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.0))
    nfev = np.asarray(history.nfev, dtype=np.float64)
    values = np.asarray(history.fun, dtype=np.float64)
    label = "best value so far" if isinstance(history, SearchHistory) else "mean value of the iteration"
    ax.plot(nfev, values, color="C0", label=label)
    finite = values[np.isfinite(values)]
    if finite.size and bool(np.all(finite > 0)):
        ax.set_yscale("log")
    ax.set_xlabel("evaluations of fun")
    ax.set_ylabel(label, color="C0")
    spread = ax.twinx()
    spread.plot(nfev, np.asarray(history.sigma, dtype=np.float64), color="C1", label="sigma")
    spread.set_ylabel("sigma (the spread)", color="C1")
    sigmas = np.asarray(history.sigma, dtype=np.float64)
    if sigmas.size and bool(np.all(sigmas[np.isfinite(sigmas)] > 0)) and np.isfinite(sigmas).any():
        spread.set_yscale("log")
    ax.set_title(str(result.get("message", ""))[:80], fontsize="small")
    return ax
