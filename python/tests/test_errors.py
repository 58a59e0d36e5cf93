"""Every bad input is a ValueError naming the value; fun's own exceptions come out unchanged."""

import math

import numpy as np
import pytest

import plateau_free
from helpers import interrupted_within, interrupting


def linear(x):
    return float(x[0])


def estimate(x=(0.0, 0.0), sigma=0.5, **options):
    return plateau_free.PlateauFreeGradient(linear, **options).estimate(x, sigma)


@pytest.mark.parametrize("bad, text", [(math.nan, "nan"), (math.inf, "inf"), (-math.inf, "-inf")])
def test_non_finite_x_and_x0(bad, text):
    with pytest.raises(ValueError, match=rf"x\[1\] = {text} is not finite"):
        estimate([0.0, bad])
    with pytest.raises(ValueError, match=rf"x0\[1\] = {text} is not finite"):
        plateau_free.minimize(linear, [0.0, bad], method="plateau", iterations=2)


def test_empty_x_and_x0():
    with pytest.raises(ValueError, match=r"x = \[\] is empty"):
        estimate([])
    with pytest.raises(ValueError, match=r"x0 = array\(\[\], dtype=float64\) is empty"):
        plateau_free.minimize(linear, np.zeros(0), method="plateau", iterations=2)


@pytest.mark.parametrize("sigma", [0.0, -1.0, math.nan, math.inf])
def test_bad_sigma(sigma):
    with pytest.raises(ValueError, match=rf"sigma = {sigma}|sigma = (NaN|inf|-?0|-1) "):
        estimate(sigma=sigma)


def test_bad_sigma0_in_minimize():
    with pytest.raises(ValueError, match="sigma0 = -0.5 is invalid: must be finite and > 0"):
        plateau_free.minimize(linear, [0.0], method="plateau", sigma0=-0.5, iterations=2)


def test_spreads_of_the_wrong_length_or_value():
    with pytest.raises(ValueError, match="spreads has length 3, expected 2"):
        estimate(sigma=[0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match=r"spreads\[1\] = 0.0 must be finite and > 0"):
        estimate(sigma=[0.1, 0.0])
    with pytest.raises(ValueError, match=r"spreads\[0\] = NaN"):
        estimate(sigma=[math.nan, 0.1])


def test_zero_samples():
    with pytest.raises(ValueError, match="samples.*0"):
        plateau_free.PlateauFreeGradient(linear, samples=0)
    with pytest.raises(ValueError, match="samples.*0"):
        plateau_free.minimize(linear, [0.0], method="plateau", samples=0, iterations=2)


def test_odd_samples_with_antithetic_pairs():
    with pytest.raises(ValueError, match="samples = 3"):
        plateau_free.PlateauFreeGradient(linear, samples=3)
    with pytest.raises(ValueError, match="samples = 5"):
        plateau_free.minimize(linear, [0.0], method="plateau", samples=5, iterations=2)
    assert estimate(samples=3, antithetic=False).shape == (2,)


def test_negative_samples_and_seed_are_rejected():
    with pytest.raises(ValueError, match=r"samples = -2 must be a whole number from 1 to 2\*\*64 - 1"):
        plateau_free.PlateauFreeGradient(linear, samples=-2)
    with pytest.raises(ValueError, match=r"seed = -1 must be a whole number from 0 to 2\*\*64 - 1"):
        plateau_free.PlateauFreeGradient(linear, seed=-1)


def test_bounds_with_lower_above_upper():
    with pytest.raises(ValueError, match=r"bounds\[1\] = \(2, 1\): lower 2 > upper 1"):
        plateau_free.minimize(linear, [0.0, 0.0], method="plateau", bounds=[(0, 1), (2, 1)], iterations=2)
    with pytest.raises(ValueError, match=r"bounds\[0\]: lower 2.0 > upper 1.0"):
        plateau_free.Adam(0.1, bounds=([2.0], [1.0]))
    with pytest.raises(ValueError, match="bounds has 3 .lower, upper. pairs, x0 has 2 coordinates"):
        plateau_free.minimize(linear, [0.0, 0.0], method="plateau", bounds=[(0, 1), (0, 1), (0, 1)], iterations=2)


@pytest.mark.parametrize("value, text", [(math.nan, "NaN"), (math.inf, "inf"), (-math.inf, "-inf")])
def test_fun_returning_nan_or_infinity(value, text):
    with pytest.raises(ValueError, match=f"f returned {text} at evaluation 0"):
        plateau_free.PlateauFreeGradient(lambda x: value).estimate([0.0], 0.1)
    with pytest.raises(ValueError, match=f"f returned {text}"):
        plateau_free.minimize(lambda x: value, [0.0], method="plateau", iterations=3)
    with pytest.raises(ValueError, match=f"f returned {text}"):
        plateau_free.PlateauFreeGradient(lambda X: np.full(len(X), value), batched=True).estimate([0.0], 0.1)


@pytest.mark.parametrize("value", ["1.0", None, [1.0, 2.0], object()])
def test_fun_returning_a_non_number(value):
    with pytest.raises(TypeError, match="fun must return a real number"):
        plateau_free.PlateauFreeGradient(lambda x: value).estimate([0.0], 0.1)


def test_batched_fun_returning_non_numbers():
    with pytest.raises((TypeError, ValueError)):
        plateau_free.PlateauFreeGradient(lambda X: ["a"] * len(X), batched=True).estimate([0.0], 0.1)
    with pytest.raises((TypeError, ValueError)):
        plateau_free.PlateauFreeGradient(lambda X: None, batched=True).estimate([0.0], 0.1)


@pytest.mark.parametrize("returned", [lambda X: np.zeros(len(X) + 1), lambda X: np.zeros((len(X), 1)), lambda X: 1.0, lambda X: []])
def test_batch_of_the_wrong_length(returned):
    with pytest.raises(ValueError, match="batched fun must return 4 values"):
        plateau_free.PlateauFreeGradient(returned, samples=4, batched=True).estimate([0.0], 0.1)


def test_bad_names_and_callables():
    with pytest.raises(ValueError, match="sampling = 'spherical'"):
        plateau_free.PlateauFreeGradient(linear, sampling="spherical")
    with pytest.raises(ValueError, match="annealer = 'linear'"):
        plateau_free.minimize(linear, [0.0], method="plateau", annealer="linear", iterations=2)
    with pytest.raises(ValueError, match="method = 'newton'"):
        plateau_free.minimize(linear, [0.0], method="newton", iterations=2)
    with pytest.raises(TypeError, match="callable"):
        plateau_free.PlateauFreeGradient(42)
    with pytest.raises(ValueError, match="lr = 0"):
        plateau_free.minimize(linear, [0.0], method="plateau", lr=0.0, iterations=2)
    with pytest.raises(ValueError, match="iterations"):
        plateau_free.Annealer.paper(0.5, 0)
    with pytest.raises(ValueError, match="orthogonal"):
        plateau_free.PlateauFreeGradient(linear, sampling="per_coordinate", orthogonal=True)


class Boom(Exception):
    pass


def test_exception_from_fun_comes_out_unchanged_and_stops_the_estimate():
    calls = []

    def exploding_objective(x):
        calls.append(1)
        raise Boom("bang")

    grad = plateau_free.PlateauFreeGradient(exploding_objective, samples=10)
    with pytest.raises(Boom, match="bang") as info:
        grad.estimate([0.0], 0.1)
    assert len(calls) == 1
    assert any(entry.name == "exploding_objective" for entry in info.traceback)
    # The estimator stays usable.
    grad2 = plateau_free.PlateauFreeGradient(lambda x: float(x[0]), samples=2)
    assert grad2.estimate([0.0], 0.1).shape == (1,)


def test_exception_from_fun_in_every_form():
    def raise_key(*_):
        raise KeyError("k")

    for options in [dict(batched=True), dict(seeded=True), dict(batched=True, seeded=True)]:
        with pytest.raises(KeyError):
            plateau_free.PlateauFreeGradient(raise_key, **options).estimate([0.0], 0.1)
    with pytest.raises(KeyError):
        plateau_free.FiniteDifference(raise_key).estimate([0.0, 1.0])
    with pytest.raises(KeyError):
        plateau_free.Spsa(raise_key).estimate([0.0, 1.0], 0.1)


def test_exception_from_fun_comes_out_of_minimize_unchanged():
    count = [0]

    def fails_later(x):
        count[0] += 1
        if count[0] == 7:
            raise Boom("seventh")
        return float(x[0])

    with pytest.raises(Boom, match="seventh") as info:
        plateau_free.minimize(fails_later, [0.0], method="plateau", iterations=100, on_failure="raise")
    assert count[0] == 7
    assert any(entry.name == "fails_later" for entry in info.traceback)
    assert info.value.result.nit == 3 and info.value.result.status == 3  # the result so far


def test_exception_from_callback_comes_out_unchanged():
    def callback(x):
        raise Boom("from the callback")

    with pytest.raises(Boom, match="from the callback"):
        plateau_free.minimize(linear, [0.0], method="plateau", iterations=10, callback=callback)


def test_keyboard_interrupt_stops_minimize_within_one_call():
    fun, count = interrupting(linear)
    result = plateau_free.minimize(fun, [0.0], method="plateau", iterations=10_000)
    assert count[0] <= 6
    assert result.status == 2 and result.message.startswith("interrupted")
    for method in ("fd", "spsa"):  # the baselines too
        fun, count = interrupting(linear)
        result = plateau_free.minimize(fun, [0.0], method=method, iterations=10_000)
        assert count[0] <= 6 and result.status == 2, method


def test_keyboard_interrupt_reaches_a_fun_without_python_bytecode():
    # `sum` runs no bytecode: the check between evaluations sees the signal. The iterations
    # (about 30 s of `sum`) end the run should every press be lost.
    with interrupted_within(5.0) as run:
        run.result = plateau_free.minimize(sum, [0.0, 0.0], method="plateau", iterations=5 * 10**6)
    assert run.result.status == 2


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_a_non_finite_final_evaluation_is_refused(bad: float) -> None:
    # Finite everywhere the loop evaluates, non-finite at the final point alone.
    calls = []

    def fun(x: np.ndarray) -> float:
        calls.append(1)
        return bad if len(calls) == 2 * 3 + 1 else float(np.sum(x**2))

    with pytest.raises(ValueError, match="the final evaluation must be finite"):
        plateau_free.minimize(fun, [1.0, 2.0], method="plateau", iterations=3)
