"""A run's state is a value: an :class:`plateau_free.AskTell` pickles (and deep-copies) after any
tell, or between an ask and its tell, and the copy finishes bit for bit as the uninterrupted run,
for every method."""

from __future__ import annotations

import copy
import json
import pickle
from typing import Any, Callable, Optional

import numpy as np
import pytest

import plateau_free

METHODS: dict[str, dict[str, Any]] = {
    "adaptive": dict(method="adaptive", budget=300, seed=5),
    "adaptive-box": dict(method="adaptive", budget=300, seed=6, bounds=[(-2, 2), (-1, 3), (-1, 0.5)], target=-np.inf),
    "plateau": dict(method="plateau", samples=8, iterations=20, seed=7, record_x=True),
    "polished": dict(method="polished", budget=300, seed=8, polish=0.5),
}


def stairs(x: np.ndarray) -> float:
    """Flat almost everywhere: the squared distance of the rounded point to (0, 1, 2) / 2."""
    return float(np.sum((np.round(2.0 * x) - np.arange(x.size)) ** 2))


Copy = Callable[[plateau_free.AskTell], plateau_free.AskTell]


def run(options: dict[str, Any], cut: Optional[tuple[int, bool]], again: Copy) -> tuple[list[bytes], Any]:
    """Every asked point and seed (bytes) and the result; copied by ``again`` after ``cut[0]``
    tells (with ``cut[1]``, between the next ask and its tell)."""
    es = plateau_free.ask_tell([0.3, -0.4, 0.1], **options)
    asked: list[bytes] = []
    tells = 0
    while True:
        if cut == (tells, False):
            es = again(es)
        if es.done:
            break
        X, seeds = es.ask()
        asked.append(X.tobytes() + seeds.tobytes())
        values = [stairs(x) for x in X]
        if cut == (tells, True):
            es = again(es)
        es.tell(values)
        tells += 1
    return asked, es.result


def same(a: Any, b: Any) -> None:
    """Two results, bit for bit: every field, arrays by their bytes (a history field by field)."""
    assert sorted(a.keys()) == sorted(b.keys())
    for key in a:
        x, y = a[key], b[key]
        if isinstance(x, plateau_free.History):
            same({k: getattr(x, k) for k in x.__slots__}, {k: getattr(y, k) for k in y.__slots__})
        elif isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), key
        elif isinstance(x, float):
            assert np.float64(x).tobytes() == np.float64(y).tobytes(), key
        else:
            assert x == y, key


def pickled(es: plateau_free.AskTell) -> plateau_free.AskTell:
    copied: plateau_free.AskTell = pickle.loads(pickle.dumps(es))
    del es  # the original is gone: the copy alone goes on
    return copied


@pytest.mark.parametrize("name", sorted(METHODS))
@pytest.mark.parametrize("again", [pickled, copy.deepcopy], ids=["pickle", "deepcopy"])
def test_resumes_bit_for_bit(name: str, again: Copy) -> None:
    options = METHODS[name]
    asked, result = run(options, None, again)
    tells = len(asked)
    assert tells > 10
    for k in sorted({0, 1, 2, tells // 2, tells - 1, tells}):
        for mid_ask in (False, True):
            if mid_ask and k == tells:
                continue
            a, r = run(options, (k, mid_ask), again)
            assert a == asked, f"{name}: points after {k} tells, mid ask {mid_ask}"
            same(r, result)


def test_copy_is_independent() -> None:
    """A copy and its original go on separately: telling one does not move the other."""
    es = plateau_free.ask_tell([0.3, -0.4, 0.1], budget=100, seed=1)
    X, _ = es.ask()
    twin = copy.deepcopy(es)
    es.tell([stairs(x) for x in X])
    assert es.nfev == 1 and twin.nfev == 0
    with pytest.raises(ValueError):
        es.tell([0.0])  # nothing asked
    twin.tell([stairs(x) for x in X])
    assert twin.nfev == 1


def test_not_a_state_is_a_value_error() -> None:
    raw = plateau_free.ask_tell([0.0], budget=10)._raw
    with pytest.raises(ValueError, match="not a saved ask-and-tell run"):
        type(raw)._from_state("{}")


def test_a_state_of_the_wrong_dimension_is_a_value_error() -> None:
    """An edited state whose start has another length than the run's points: refused when
    read, naming the vector, not a crash at a later ask."""
    es = plateau_free.ask_tell([0.0, 0.0], budget=50, seed=2)
    X, _ = es.ask()
    es.tell([stairs(x) for x in X])
    state = json.loads(es._raw._state())
    state["run"]["Adaptive"]["x0"].append(0.5)
    with pytest.raises(ValueError, match="x0 has length 3, expected 2"):
        type(es._raw)._from_state(json.dumps(state))
