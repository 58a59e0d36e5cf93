"""``_native._drive``: the adaptive and polished runs on the library's driver with a Python
evaluator give the bits of :func:`plateau_free.minimize`; a callback's truthy return ends the run
with the library's interrupt, and the library's checkpoint resumes it bit for bit."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import plateau_free
from plateau_free import _native
from plateau_free._ask_tell import _native_run
from plateau_free._evaluate import _Evaluator
from plateau_free._options import _check_call

TARGET = np.array([1.0, -2.0, 3.0])
OPTIONS: dict[str, Any] = dict(seed=3, budget=2000)


def staircase(x: np.ndarray) -> float:
    return float(np.sum((np.round(x) - TARGET) ** 2))


def driven(method: str, **settings: Any) -> tuple[dict[str, Any], Any, list[Any]]:
    """``staircase`` from zeros, run by ``_drive`` as ``minimize`` builds the run."""
    chosen, x0, checked = _check_call("minimize", method, np.zeros(3), dict(OPTIONS))
    run, _, _ = _native_run(chosen, x0, checked)
    evaluate = _Evaluator(staircase)
    result: tuple[dict[str, Any], Any, list[Any]] = _native._drive(
        run, lambda points, seeds: evaluate(np.asarray(points), seeds).tolist(), **settings
    )
    return result


@pytest.mark.parametrize("method", ["adaptive", "polished"])
def test_driven_equals_minimize(method: str) -> None:
    alone = plateau_free.minimize(staircase, np.zeros(3), method=method, **OPTIONS)
    raw, why, rows = driven(method, keep=8)
    assert why is None and raw["stop"] in ("Done", "Budget")
    assert raw["x"].tobytes() == alone.x.tobytes()
    assert (raw["fun"], raw["nfev"], raw["nit"]) == (alone.fun, alone.nfev, alone.nit)
    assert 8 <= len(rows) <= 17 and rows[-1][:2] == (raw["nit"], raw["nfev"])


@pytest.mark.parametrize("method", ["adaptive", "polished"])
def test_stopped_by_the_callback_and_resumed(tmp_path: Path, method: str) -> None:
    alone, _, _ = driven(method)
    path = tmp_path / "run.json"
    stopped, why, _ = driven(method, checkpoint=path, callback=lambda it, nfev, best, sigma: it >= 5)
    assert why == "callback" and stopped["stop"] == "Interrupted" and stopped["nit"] == 5
    resumed, why, _ = driven(method, checkpoint=path)
    assert why is None and resumed["x"].tobytes() == alone["x"].tobytes()
    assert (resumed["fun"], resumed["nfev"]) == (alone["fun"], alone["nfev"])


def test_the_evaluators_exception_comes_back_unchanged() -> None:
    chosen, x0, checked = _check_call("minimize", "adaptive", np.zeros(3), dict(OPTIONS))
    run, _, _ = _native_run(chosen, x0, checked)

    def refuse(points: Any, seeds: Any) -> Any:
        raise LookupError("no values here")

    with pytest.raises(LookupError, match="no values here"):
        _native._drive(run, refuse)
