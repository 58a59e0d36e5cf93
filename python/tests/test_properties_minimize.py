"""Property-based tests (Hypothesis) of ``minimize`` (every method) and of the estimators with
objectives that raise or return what is not a number, and of ``minimize`` with any start,
budget, seed, counts, bounds, target and rate.

The contract they hold every input to, and how they stay deterministic: ``properties.py``.
"""

import math

import numpy as np
import pytest

from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import plateau_free
from properties import (
    EXPECTED,
    HUGE_INT,
    props,
    no_silent_complex,
    Boom,
    attempt,
    assert_finite,
    ODD_FLOATS,
    real_arrays,
    any_arrays,
    plain,
    spreads,
    whole_numbers,
    seeds,
    smooth,
    smooth_batch,
    objective,
)

# Hypothesis draws float16 values through a cast that may overflow (to the infinity it means).
pytestmark = pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning")

# ---------------------------------------------------------------------------------------------
# Objectives that misbehave

BAD_VALUES = [None, "1.0", b"1", 1j, np.complex128(1 + 1j), np.array([1.0, 2.0]), np.array([1.0]), [1.0],
              HUGE_INT, object(), {}, np.array(1 + 1j), math.nan, math.inf, -math.inf, Boom]  # fmt: skip
BAD_BATCHES = ["longer", "2-d", "none", "words", "complex", "objects", "nan", "inf", Boom]


def bad_batch(kind, n):
    return {
        "longer": lambda: np.zeros(n + 1),
        "2-d": lambda: np.zeros((n, 2)),
        "none": lambda: None,
        "words": lambda: ["a"] * n,
        "complex": lambda: np.full(n, 1 + 1j),
        "objects": lambda: [object()] * n,
        "nan": lambda: np.where(np.arange(n) == n - 1, np.nan, 0.0),
        "inf": lambda: np.full(n, -np.inf),
    }[kind]()


@no_silent_complex
@props(800)
@given(
    method=st.sampled_from(["adaptive", "plateau", "polished", "fd", "spsa"]),
    batched=st.booleans(),
    seeded=st.booleans(),
    bad=st.data(),
    at=st.integers(1, 40),
    x0=real_arrays(hnp.array_shapes(min_dims=0, max_dims=2, min_side=1, max_side=3)).filter(lambda a: plain(a) is True),
    seed=st.integers(0, 2**64 - 1),
)
def test_minimize_with_an_objective_that_raises_or_returns_non_numbers(method, batched, seeded, bad, at, x0, seed):
    """From its ``at``-th call on, ``fun`` returns something bad (or raises): the run ends in
    an exception of the right type (the objective's own exception unchanged), else it returns
    a valid result."""
    what = bad.draw(st.sampled_from(BAD_BATCHES if batched else BAD_VALUES))
    boom = Boom("from the objective")
    calls = [0]
    returned_bad = [False]

    def fun(x, *seeds):
        calls[0] += 1
        if calls[0] < at:
            return smooth_batch(x) if batched else smooth(x)
        returned_bad[0] = True
        if what is Boom:
            raise boom
        return bad_batch(what, len(x)) if batched else what

    options = dict(budget=40, seed=seed, batched=batched, seeded=seeded)
    if method in ("adaptive", "plateau", "polished"):
        options["on_failure"] = "raise"  # the baselines end on a failure anyway
    if method == "polished":
        options["polish"] = 0.5
    result, error = None, None
    try:
        result = plateau_free.minimize(fun, x0, method=method, **options)
    except Boom as e:
        assert e is boom and what is Boom and returned_bad[0]
        return
    except EXPECTED as e:
        error = e
        assert str(error).strip()
    if not returned_bad[0]:
        assert error is None, f"refused without a bad value: {error!r}"
        assert_finite(np.asarray(result.x), np.shape(x0))
        assert math.isfinite(result.fun) and result.nfev <= 40
        return
    assert error is not None, f"fun returned {what!r} and minimize returned {result!r}"
    if not batched and what is not None and isinstance(what, float):
        assert isinstance(error, ValueError) and not isinstance(error, TypeError)  # NaN, inf
    elif not batched:
        assert isinstance(error, TypeError), repr(error)  # not a number
    elif what in ("longer", "2-d", "nan", "inf"):
        assert isinstance(error, ValueError), repr(error)


@no_silent_complex
@props(100)
@given(st.sampled_from(BAD_VALUES), st.sampled_from(["plateau", "fd", "spsa"]), st.booleans())
def test_estimators_with_an_objective_that_misbehaves(what, kind, seeded):
    boom = Boom("raised by fun")

    def fun(x, *seed):
        if what is Boom:
            raise boom
        return what

    make = {"plateau": plateau_free.PlateauFreeGradient, "fd": plateau_free.FiniteDifference, "spsa": plateau_free.Spsa}
    estimator = make[kind](fun, seeded=seeded)
    with pytest.raises(Exception) as info:
        estimator.estimate([0.5, 1.5], 0.1)
    error = info.value
    if what is Boom:
        assert error is boom
    elif isinstance(what, float):
        assert isinstance(error, ValueError) and "returned" in str(error)
    else:
        assert isinstance(error, TypeError) and "fun must return a real number" in str(error)
    # The estimator stays usable after the error.
    assert estimator.nfev >= 1


# ---------------------------------------------------------------------------------------------
# minimize's options of any type and size


@no_silent_complex
@props(800)
@given(
    method=st.sampled_from(["adaptive", "plateau", "paper", "polished", "fd", "spsa", None]),
    x0=any_arrays(),
    budget=st.one_of(st.none(), whole_numbers(-2, 80)),
    seed=seeds(),
    extra=st.data(),
    stop_after=st.integers(1, 4),
)
def test_minimize_with_any_x0_budget_seed_and_counts(method, x0, budget, seed, extra, stop_after):
    chosen = {None: "adaptive", "paper": "plateau"}.get(method, method)
    options = {}
    if chosen in ("plateau", "polished"):
        options["samples"] = extra.draw(st.one_of(st.none(), whole_numbers(-2, 8)), label="samples")
    if chosen in ("plateau", "fd", "spsa"):
        options["iterations"] = extra.draw(st.one_of(st.none(), whole_numbers(-2, 6, huge=False)), label="iterations")
    if chosen in ("adaptive", "polished"):
        # Not of 2**40 and more within a budget as large: see the last regression test.
        options["population"] = extra.draw(st.one_of(st.none(), whole_numbers(-2, 12, huge=False)), label="population")
        options["sigma0"] = extra.draw(st.one_of(st.none(), spreads()), label="sigma0")
    if chosen == "polished":
        options["polish"] = extra.draw(st.sampled_from([None, 0.0, 0.5, 0.99, 1.0, -0.1, math.nan, "x", HUGE_INT]), label="polish")
    if chosen in ("plateau", "spsa"):
        options["sigma0"] = extra.draw(st.one_of(st.none(), spreads()), label="sigma0")
    calls = [0]

    def stop(x):  # every run ends within a few iterations, whatever the budget
        calls[0] += 1
        return calls[0] >= stop_after

    def run():
        return plateau_free.minimize(
            smooth, x0, method=method, budget=budget, seed=seed, callback=stop,
            **{k: v for k, v in options.items() if v is not None},
        )  # fmt: skip

    result, error = attempt(run)
    if plain(x0) is False:
        assert error is not None, f"x0 = {x0!r} not refused"
    if error is None:
        assert_finite(np.asarray(result.x), np.shape(x0))
        assert math.isfinite(result.fun)
        assert isinstance(result.nfev, int) and result.nfev >= 1
        if budget is not None:
            assert result.nfev <= int(budget)
        assert result.status in (0, 1, 99) and result.message


@props(400)
@given(
    method=st.sampled_from(["adaptive", "plateau", "polished", "fd", "spsa"]),
    bounds=st.one_of(
        st.tuples(st.sampled_from(ODD_FLOATS + [None, -1.0, 0.0, HUGE_INT, "0"]), st.sampled_from(ODD_FLOATS + [None, 1.0, 2.0, -HUGE_INT])),
        st.lists(st.tuples(st.sampled_from([None, -1.0, 0.0, 1e300]), st.sampled_from([None, 1.0, 2.0, 1e308])), min_size=0, max_size=3),
        st.sampled_from([None, "box", 3, [1, 2, 3], [(0, 1, 2)], [(1j, 2)], np.array([[0.0, 1.0]] * 2)]),
    ),
    target=st.one_of(st.none(), st.sampled_from(ODD_FLOATS + [HUGE_INT, "0", True])),
    lr=st.one_of(st.none(), st.sampled_from(ODD_FLOATS + [HUGE_INT, 0.01, "0.1"])),
)
def test_minimize_with_any_bounds_target_and_rate(method, bounds, target, lr):
    options = {}
    if target is not None and method in ("adaptive", "polished"):
        options["target"] = target
    if lr is not None and method in ("plateau", "polished", "fd", "spsa"):
        options["lr"] = lr
    x0 = [0.5, 0.5]
    result, error = attempt(
        lambda: plateau_free.minimize(smooth, x0, method=method, budget=30, bounds=bounds, **options)
    )
    if error is None:
        assert_finite(np.asarray(result.x), (2,))
        assert math.isfinite(result.fun) and result.nfev <= 30
