"""Property-based tests (Hypothesis) of ``ask_tell``: ask/tell sequences in any order, with
wrong calls in between that must change nothing, and options of any kind.

The contract they hold every input to, and how they stay deterministic: ``properties.py``.
"""

import math

import numpy as np
import pytest

from hypothesis import given
from hypothesis import strategies as st

import plateau_free
from properties import (
    HUGE_INT,
    props,
    attempt,
    assert_finite,
    any_arrays,
    plain,
    whole_numbers,
    seeds,
    smooth,
    stairs,
)

# Hypothesis draws float16 values through a cast that may overflow (to the infinity it means).
pytestmark = pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning")

# ---------------------------------------------------------------------------------------------
# ask and tell in any order




MISTAKES = ["ask again", "shorter", "longer", "nothing", "nan", "inf", "none", "words", "complex",
            "huge int", "result", "best", "nested"]  # fmt: skip


def make_run(method, x0, seed):
    """A run that refuses non-finite values (``on_failure='raise'``), to test the refusals."""
    if method == "plateau":
        return plateau_free.ask_tell(x0, method=method, iterations=6, seed=seed, on_failure="raise")
    return plateau_free.ask_tell(x0, method=method, budget=40, seed=seed, on_failure="raise")


def make_mistake(es, mistake, X):
    """One wrong call while ``X`` waits for its values: an error of the right type, which
    changes nothing."""
    k = len(X)
    good = [stairs(x) for x in X]
    told = {
        "shorter": good[:-1],
        "longer": good + [1.0],
        "nothing": [],
        "nan": good[:-1] + [math.nan],
        "inf": [math.inf] + good[1:],
        "none": None,
        "words": ["one"] * k,
        "complex": [1j] * k,
        "huge int": [HUGE_INT] * k,
        "nested": [[1.0, 2.0], [3.0]],
    }
    if mistake == "ask again":
        with pytest.raises(ValueError, match="ask called twice"):
            es.ask()
    elif mistake == "result":
        with pytest.raises(ValueError, match="not ended"):
            es.result
    elif mistake == "best":
        best = es.best
        if best is not None:
            assert_finite(best[0], X.shape[1:])
            assert math.isfinite(best[1])
    else:
        expected = TypeError if mistake in ("none", "words", "complex", "nested") else ValueError
        with pytest.raises(expected) as info:
            es.tell(told[mistake])
        assert str(info.value).strip()


@props(150)
@given(
    method=st.sampled_from(["adaptive", "plateau", "polished"]),
    x0=st.sampled_from([[0.3], [0.2, -0.4], np.zeros((2, 2)), np.array(0.7)]),
    seed=st.integers(0, 2**64 - 1),
    plan=st.lists(st.lists(st.sampled_from(MISTAKES), max_size=3), min_size=1, max_size=8),
)
def test_ask_tell_in_any_order_ends_as_the_clean_run(method, x0, seed, plan):
    """Wrong calls (asking twice, telling the wrong count, NaN, infinities, non-numbers, the
    result too early) between the right ones: each an error of the right type that changes
    nothing, and the run ends bit for bit as the run without them."""
    clean = make_run(method, x0, seed)
    while not clean.done:
        X, _ = clean.ask()
        clean.tell([stairs(x) for x in X])
    es = make_run(method, x0, seed)
    with pytest.raises(ValueError, match="tell without ask"):
        es.tell([1.0])
    step = 0
    while not es.done:
        X, seeds = es.ask()
        assert_finite(X, X.shape) and X.shape[1:] == np.shape(x0)
        assert seeds.dtype == np.uint64 and len(seeds) == len(X) >= 1
        for mistake in plan[step % len(plan)]:
            make_mistake(es, mistake, X)
        es.tell(np.array([stairs(x) for x in X]))
        if method != "plateau":
            assert es.nfev <= 40
        step += 1
    with pytest.raises(ValueError, match="has ended"):
        es.ask()
    with pytest.raises(ValueError, match="tell without ask"):
        es.tell([1.0])
    result, expected = es.result, clean.result
    np.testing.assert_array_equal(result.x, expected.x)
    assert result.x.shape == np.shape(x0) and np.all(np.isfinite(result.x))
    assert result.fun == expected.fun and math.isfinite(result.fun)
    assert result.nfev == expected.nfev and result.nit == expected.nit


@props(300)
@given(
    x0=any_arrays(),
    method=st.sampled_from(["adaptive", "plateau", "polished", "fd", "spsa", "newton", None, 3]),
    budget=st.one_of(st.none(), whole_numbers(-2, 50)),
    seed=seeds(),
)
def test_ask_tell_options_of_any_kind(x0, method, budget, seed):
    options = dict(iterations=3) if method == "plateau" and budget is None else {}
    es, error = attempt(lambda: plateau_free.ask_tell(x0, method=method, budget=budget, seed=seed, **options))
    if plain(x0) is False:
        assert error is not None
    if error is not None:
        return
    for _ in range(3):  # a few rounds: the points are finite and shaped like x0
        if es.done:
            break
        asked, error = attempt(es.ask)  # x0 near 1e308: the points overflow (a ValueError)
        if error is not None:
            return
        X, seeds = asked
        assert_finite(X, (len(seeds),) + np.shape(x0))
        es.tell([smooth(x) for x in X])
