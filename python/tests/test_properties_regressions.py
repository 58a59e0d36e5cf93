"""Regression tests of the bugs the property-based tests (``test_properties_*.py``) found:
non-finite or non-numeric values told or returned, integers too large for a float, populations
larger than the budget or than memory, complex inputs, huge schedules.

The contract they hold every input to, and how they stay deterministic: ``properties.py``.
"""

import math

import numpy as np
import pytest

import plateau_free
from plateau_free import OptionTypeError
from properties import HUGE_INT, seeds, smooth, smooth_batch, stairs

# Hypothesis draws float16 values through a cast that may overflow (to the infinity it means).
pytestmark = pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning")

# ---------------------------------------------------------------------------------------------
# Regression tests: the bugs the properties found.


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_ask_tell_refuses_a_non_finite_final_value(bad):
    # The paper loop's final evaluation took any value: result.fun was NaN, silently
    # (minimize refuses it).
    es = plateau_free.ask_tell([0.25, 0.5], method="plateau", iterations=1)
    X, _ = es.ask()
    es.tell([stairs(x) for x in X])
    X, seeds = es.ask()
    assert len(X) == 1 and not es.done
    with pytest.raises(ValueError, match=r"at evaluation 2, point \[0\.\d*, 0\.\d*\]: tell finite values"):
        es.tell([bad])
    assert not es.done
    es.tell([3.0])
    assert es.done and es.result.fun == 3.0


@pytest.mark.parametrize(
    "values, error",
    [(None, TypeError), ([1j, 1.0], TypeError), (np.array([1 + 0j, 2 + 0j]), TypeError), ({1.0, 2.0}, TypeError),
     (["one", "two"], TypeError), ([HUGE_INT, 1.0], ValueError)],
)  # fmt: skip
def test_tell_of_non_numbers_is_a_clear_error(values, error):
    # tell(None) said "f returned NaN", a complex value was told by its real part (a
    # ComplexWarning aside), an int too large for a float was an OverflowError.
    es = plateau_free.ask_tell([0.0], method="plateau", iterations=2)
    X, _ = es.ask()
    with pytest.raises(error, match="must be real numbers, one per asked point"):
        es.tell(values)
    es.tell([1.0, 2.0])  # the same points still waited for their values


@pytest.mark.parametrize(
    "options",
    [dict(sigma0=HUGE_INT), dict(target=-HUGE_INT), dict(bounds=[(0, HUGE_INT)]),
     dict(method="plateau", lr=HUGE_INT), dict(method="plateau", sigma_min=HUGE_INT),
     dict(method="fd", step=HUGE_INT)],
)  # fmt: skip
def test_an_int_too_large_for_a_float_is_a_value_error(options):
    # An OverflowError (neither a ValueError nor a TypeError) before.
    with pytest.raises(ValueError, match="too large for a float"):
        plateau_free.minimize(smooth, [0.5], budget=30, **options)


def test_x0_with_an_int_too_large_for_a_float_is_a_value_error():
    with pytest.raises(ValueError, match="x0 = .* is not an array of finite numbers"):
        plateau_free.minimize(smooth, [0.5, HUGE_INT], budget=30)


@pytest.mark.parametrize("population, budget", [(2**62, None), (2**62, 100), (101, 100), (2**64 - 1, 2**40)])
def test_a_population_larger_than_the_budget_is_refused(population, budget):
    # A PanicException ("capacity overflow") or an aborted interpreter (a failed allocation)
    # before: the whole generation was drawn before the budget cut it.
    with pytest.raises(ValueError, match="population = .* is more than .*budget"):
        plateau_free.minimize(smooth, [0.5], population=population, budget=budget)
    with pytest.raises(ValueError, match="population = .* is more than .*budget"):
        plateau_free.ask_tell([0.5], population=population, budget=budget)
    assert plateau_free.minimize(smooth, [0.5], population=100, budget=100).nfev <= 100


@pytest.mark.parametrize(
    "final, error",
    [("1.0", TypeError), (b"1", TypeError), (np.complex128(1 + 0j), TypeError), (np.array([1.0]), TypeError)],
)  # fmt: skip
def test_the_final_evaluation_takes_what_the_loop_takes(final, error):
    # The paper loop's final evaluation (in Python) took a string as a number, and a complex
    # number by its real part; the loop's evaluations (in Rust) refuse both.
    calls = [0]

    def fun(x):
        calls[0] += 1
        return final if calls[0] == 2 * 3 + 1 else smooth(x)

    with pytest.raises(error, match="fun must return a real number"):
        plateau_free.minimize(fun, [0.5], method="plateau", iterations=3)


@pytest.mark.parametrize(
    "final, error, text",
    [(lambda X: np.zeros(3), ValueError, "must return 1 value"), (lambda X: ["1.5"], TypeError, "1 real number"),
     (lambda X: np.array([2 + 0j]), TypeError, "1 real number"), (lambda X: None, TypeError, "1 real number")],
)  # fmt: skip
def test_the_final_batched_evaluation_checks_the_batch(final, error, text):
    # It took the first of any number of values, and strings and complex numbers as numbers.
    calls = [0]

    def fun(X):
        calls[0] += 1
        return final(X) if calls[0] == 4 else smooth_batch(X)

    with pytest.raises(error, match=text):
        plateau_free.minimize(fun, [0.5], method="plateau", iterations=3, batched=True)


# Found by the properties above, fixed in the Rust extension (python/src) or the library (src/).


def test_annealer_sigmas_of_a_huge_schedule_is_an_error_not_a_panic():
    # PanicException: capacity overflow (and a failed allocation, aborting the interpreter,
    # for 2**40 iterations).
    with pytest.raises((ValueError, MemoryError), match="iterations"):
        plateau_free.Annealer("cosine", iterations=2**62).sigmas()


@pytest.mark.filterwarnings("ignore::numpy.exceptions.ComplexWarning")
def test_complex_x_sigma_and_gradient_are_refused():
    grad = plateau_free.PlateauFreeGradient(smooth)
    with pytest.raises(OptionTypeError, match="x = "):
        grad.estimate(np.array([0.5 + 1j]), 0.1)
    with pytest.raises(OptionTypeError, match="sigma = "):
        grad.estimate([0.5], np.array([0.1 + 1j]))
    with pytest.raises(OptionTypeError, match="gradient = "):
        plateau_free.Adam().step([0.5], np.array([1 + 1j]))


@pytest.mark.filterwarnings("ignore::numpy.exceptions.ComplexWarning")
def test_a_batched_fun_returning_complex_numbers_is_refused():
    with pytest.raises(TypeError, match="batched fun must return"):
        plateau_free.minimize(lambda X: np.full(len(X), 1 + 1j), [0.5], budget=20, batched=True)


@pytest.mark.filterwarnings("ignore::numpy.exceptions.ComplexWarning")
@pytest.mark.parametrize("value", [np.complex128(1 + 1j), np.complex64(2 + 0j)])
def test_fun_returning_a_numpy_complex_number_is_refused(value):
    # Python's complex is refused (TypeError); numpy's was taken by its real part.
    with pytest.raises(TypeError, match="fun must return a real number"):
        plateau_free.PlateauFreeGradient(lambda x: value).estimate([0.5], 0.1)


def test_a_population_too_large_for_memory_is_an_error_not_a_panic():
    # Within a (huge) budget: PanicException "capacity overflow" (and an aborted interpreter
    # for populations of 2**40 and so).
    with pytest.raises(ValueError, match="population"):
        plateau_free.minimize(smooth, [0.5], population=2**62, budget=2**63)
