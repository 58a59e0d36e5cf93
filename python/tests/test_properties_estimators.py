"""Property-based tests (Hypothesis) of the estimators, ``Annealer`` and ``Adam``: arrays of any
shape and dtype (floats of every width, ints, bools, complex numbers, objects, strings; NaN
and infinities; empty and 0-d arrays), spreads from 5e-324 to 1e300 (and 0, negative, NaN,
infinite), options, schedules, seeds and counts of any integer size and type.

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
    HUGE_INT,
    props,
    no_silent_complex,
    attempt,
    assert_finite,
    ODD_FLOATS,
    real_arrays,
    any_arrays,
    plain,
    spreads,
    plain_spread,
    whole_numbers,
    seeds,
    smooth,
    objective,
)

# Hypothesis draws float16 values through a cast that may overflow (to the infinity it means).
pytestmark = pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning")

# ---------------------------------------------------------------------------------------------
# The estimators


@st.composite
def estimators(draw):
    """``(kind, make)``: an estimator's name and a function making it, with any options."""
    kind = draw(st.sampled_from(["plateau", "fd", "spsa"]))
    batched, seeded = draw(st.booleans()), draw(st.booleans())
    fun = objective(batched, seeded)
    seed = draw(st.integers(0, 2**64 - 1))
    if kind == "plateau":
        samples = draw(st.integers(1, 9))
        options = dict(
            samples=samples,
            sampling=draw(st.sampled_from(["radial", "per_coordinate", "gaussian", plateau_free.Sampling.Radial])),
            antithetic=draw(st.booleans()),
            orthogonal=draw(st.booleans()),
            parallel=draw(st.booleans()),
        )
        return kind, lambda: plateau_free.PlateauFreeGradient(fun, seed=seed, batched=batched, seeded=seeded, **options)
    if kind == "fd":
        step = draw(st.one_of(st.sampled_from(ODD_FLOATS), st.floats(1e-8, 1.0)))
        return kind, lambda: plateau_free.FiniteDifference(fun, step=step, seed=seed, batched=batched, seeded=seeded)
    return kind, lambda: plateau_free.Spsa(fun, seed=seed, batched=batched, seeded=seeded)


@no_silent_complex
@props(1000)
@given(estimators(), any_arrays(), spreads())
def test_estimate_is_finite_and_shaped_like_x_or_an_error(estimator, x, sigma):
    kind, make = estimator
    made, error = attempt(make)
    if error is not None:
        return  # a refused option (odd samples with pairs, a bad step...)
    gradient, error = attempt(lambda: made.estimate(x, sigma))
    valid_x, valid_sigma = plain(x), plain_spread(sigma, kind, x)
    if valid_x is False or valid_sigma is False:
        assert error is not None, f"estimate({x!r}, {sigma!r}) = {gradient!r}: not refused"
    elif valid_x and (valid_sigma or kind == "fd") and 1e-8 <= getattr(made, "step", 1.0) <= 1e6:
        assert error is None, f"estimate({x!r}, {sigma!r}) refused: {error!r}"
    if error is None:
        assert_finite(gradient, np.shape(x))


@props(400)
@given(
    st.sampled_from(["plateau", "fd", "spsa"]),
    real_arrays(hnp.array_shapes(min_dims=0, max_dims=2, min_side=1, max_side=3)),
    st.sampled_from(ODD_FLOATS + [1.0, 1e-6, 1e6]),
    st.sampled_from([1.0, 1e-300, 1e300, 1e308]),
)
def test_huge_and_tiny_spreads_and_values(kind, x, sigma, scale):
    # f of any size (up to 1e308 a unit): a finite gradient or a ValueError naming the overflow.
    def fun(p):
        return scale * smooth(p)

    make = {
        "plateau": lambda: plateau_free.PlateauFreeGradient(fun, samples=4),
        "fd": lambda: plateau_free.FiniteDifference(fun, step=sigma if math.isfinite(sigma) and sigma > 0 else 1e-3),
        "spsa": lambda: plateau_free.Spsa(fun),
    }[kind]
    gradient, error = attempt(lambda: make().estimate(x, sigma))
    if error is None:
        assert_finite(gradient, np.shape(x))
    else:
        assert isinstance(error, ValueError)


@props(600)
@given(
    samples=whole_numbers(),
    seed=seeds(),
    sampling=st.one_of(st.sampled_from(["radial", "Per-Coordinate", "gaussian", "spherical", "", None, 1]), st.text(max_size=3)),
    flags=st.lists(st.one_of(st.booleans(), st.sampled_from([np.True_, 0, 1, None, "yes"])), min_size=5, max_size=5),
)
def test_estimator_options_of_any_type_and_size(samples, seed, sampling, flags):
    antithetic, batched, seeded, orthogonal, parallel = flags
    fun = objective(batched is True or batched is np.True_, seeded is True or seeded is np.True_)
    made, error = attempt(
        lambda: plateau_free.PlateauFreeGradient(
            fun, samples=samples, sampling=sampling, antithetic=antithetic, seed=seed, batched=batched,
            seeded=seeded, orthogonal=orthogonal, parallel=parallel,
        )  # fmt: skip
    )
    if error is not None:
        return
    assert isinstance(made.samples, int) and made.samples >= 1 and 0 <= made.seed < 2**64
    # Every count runs or is refused: a count too large for memory is a ValueError, never an
    # abort (counts between 2**6 and 2**45 would run for long and are not tried).
    if made.samples <= 64 or made.samples >= 2**45:
        gradient, error = attempt(lambda: made.estimate([0.5, -0.25], 0.1))
        if error is None:
            assert_finite(gradient, (2,))
        else:
            assert made.samples <= 64 or "memory" in str(error)
    for est in (plateau_free.FiniteDifference, plateau_free.Spsa):
        other, error = attempt(lambda: est(fun, seed=seed, batched=batched, seeded=seeded))
        if error is None:
            assert_finite(other.estimate([0.5, -0.25], 0.1), (2,))



# ---------------------------------------------------------------------------------------------
# Annealer and Adam


@props(800)
@given(
    schedule=st.one_of(st.sampled_from(["paper", "constant", "exponential", "cosine", "Cosine", "linear", ""]), st.sampled_from([None, 1, b"paper"])),
    sigma0=st.one_of(st.sampled_from(ODD_FLOATS), st.floats(), st.sampled_from([HUGE_INT, "0.5", None, True])),
    sigma_min=st.one_of(st.sampled_from(ODD_FLOATS), st.floats()),
    iterations=whole_numbers(-2, 50),
    warmup=st.one_of(st.sampled_from([0.0, 0.5, 0.999, 1.0, -0.1, math.nan, math.inf]), st.floats(0, 1)),
    at=st.lists(st.one_of(st.integers(0, 2**64 - 1), st.integers(-3, 60), st.sampled_from([2**64, 1.5, "1", True])), max_size=4),
)
def test_annealer_of_any_schedule(schedule, sigma0, sigma_min, iterations, warmup, at):
    annealer, error = attempt(lambda: plateau_free.Annealer(schedule, sigma0, sigma_min, iterations, warmup))
    if error is not None:
        return
    assert annealer.iterations >= 1
    for i in at:
        sigma, error = attempt(lambda: annealer.sigma(i))
        if error is None:
            assert math.isfinite(sigma) and sigma > 0, (i, sigma)
    if annealer.iterations <= 10**5:  # sigmas() holds one float per iteration
        sigmas = annealer.sigmas()
        assert_finite(sigmas, (annealer.iterations,))
        assert np.all(sigmas > 0)
    for shortcut in (plateau_free.Annealer.paper, plateau_free.Annealer.constant):
        other, error = attempt(lambda: shortcut(sigma0, iterations))
        if error is None:
            assert math.isfinite(other.sigma(0)) and other.sigma(0) > 0


@no_silent_complex
@props(800)
@given(
    lr=st.one_of(st.sampled_from(ODD_FLOATS + [0.02, 1.0, 1e6]), st.sampled_from([HUGE_INT, "0.1", None])),
    betas=st.tuples(st.sampled_from([0.0, 0.9, 0.999999, 1.0, -0.5, math.nan]), st.sampled_from([0.0, 0.999, 1.0, math.nan])),
    epsilon=st.sampled_from([1e-8, 5e-324, 0.0, -1.0, 1e308, math.inf]),
    bounded=st.booleans(),
    x=any_arrays(),
    gradient=st.one_of(any_arrays(), st.just("same shape")),
    steps=st.integers(1, 3),
)
def test_adam_steps_with_any_input(lr, betas, epsilon, bounded, x, gradient, steps):
    n = max(int(np.size(x)) if plain(x) is not None else 1, 1)
    bounds = ([-1.0] * n, [1.0] * n) if bounded else None
    adam, error = attempt(lambda: plateau_free.Adam(lr, betas[0], betas[1], epsilon, bounds))
    if error is not None:
        return
    if isinstance(gradient, str):
        try:
            gradient = np.ones(np.shape(x))
        except ValueError:  # a ragged x has no shape; whatever the gradient, x is refused
            gradient = np.ones(1)
    current = x
    for _ in range(steps):
        stepped, error = attempt(lambda: adam.step(current, gradient))
        if plain(x) is False or plain(gradient) is False:
            assert error is not None, f"Adam.step({x!r}, {gradient!r}) not refused"
        if error is not None:
            return
        assert_finite(stepped, np.shape(x))
        if bounded:
            assert np.all((stepped >= -1.0) & (stepped <= 1.0))
        current = stepped
