"""The budget is a ceiling (``nfev <= budget``, the paper loop's final evaluation
included), the start counts (a method that returns the best point seen is never worse than
``f(x0)``), and bounds are a promise (``fun`` is never called outside the box)."""

import re

import numpy as np
import pytest

import plateau_free
from helpers import staircase

X0 = [0.2, -0.3, 0.4]


class Counted:
    """``staircase`` that counts its calls and records every point."""

    def __init__(self):
        self.points = []

    def __call__(self, x):
        self.points.append(np.array(x, dtype=float))
        return staircase(x)


PER_ITERATION = {"plateau": 2, "spsa": 2, "fd": 2 * len(X0)}


@pytest.mark.parametrize("method", ["plateau", "fd", "spsa"])
@pytest.mark.parametrize("budget", [1, 2, 3, 4, 5, 6, 7, 8, 9, 13, 101, 400])
@pytest.mark.parametrize("final_evaluation", [True, False])
def test_the_paper_loop_spends_at_most_its_budget(method, budget, final_evaluation):
    # The final evaluation counts against the budget: the loop runs (budget - final) // samples
    # iterations, so that budget + 1 evaluations are never made.
    per = PER_ITERATION[method]
    final = int(final_evaluation)
    fun = Counted()
    iterations = (budget - final) // per
    if iterations < 1:
        with pytest.raises(ValueError, match=re.escape(f"budget = {budget} cannot pay for one iteration ({per} evaluations)")):
            plateau_free.minimize(fun, X0, method=method, budget=budget, final_evaluation=final_evaluation)
        assert fun.points == []
        return
    result = plateau_free.minimize(fun, X0, method=method, budget=budget, final_evaluation=final_evaluation)
    assert result.nit == iterations
    assert result.nfev == len(fun.points) == iterations * per + final <= budget
    assert budget - result.nfev < per  # as many iterations as the budget pays for


@pytest.mark.parametrize("samples", [2, 4, 8, 16])
@pytest.mark.parametrize("budget", [3, 9, 17, 33, 100])
def test_samples_and_budget(samples, budget):
    fun = Counted()
    if budget - 1 < samples:  # samples > budget - 1: one iteration and the final evaluation do not fit
        with pytest.raises(ValueError, match=f"give a budget of at least {samples + 1} or final_evaluation=False"):
            plateau_free.minimize(fun, X0, method="plateau", samples=samples, budget=budget)
        return
    result = plateau_free.minimize(fun, X0, method="plateau", samples=samples, budget=budget)
    assert result.nfev == len(fun.points) == (budget - 1) // samples * samples + 1 <= budget


def test_iterations_beyond_the_budget_are_refused():
    with pytest.raises(ValueError, match="iterations = 50 of 2 evaluations and the final evaluation need 101, more than budget = 100"):
        plateau_free.minimize(staircase, X0, method="plateau", iterations=50, budget=100)
    assert plateau_free.minimize(staircase, X0, method="plateau", iterations=49, budget=100).nfev == 99
    assert plateau_free.minimize(staircase, X0, method="plateau", iterations=50, budget=100, final_evaluation=False).nfev == 100


@pytest.mark.parametrize("budget", [5, 9, 101])
def test_ask_tell_paper_loop_spends_at_most_its_budget(budget):
    es = plateau_free.ask_tell(X0, method="plateau", budget=budget)
    told = 0
    while not es.done:
        X, _ = es.ask()
        es.tell([staircase(x) for x in X])
        told += len(X)
    assert es.result.nfev == told <= budget


@pytest.mark.parametrize("method", ["adaptive", "polished"])
@pytest.mark.parametrize("budget", [1, 2, 3, 7, 50, 333])
def test_the_adaptive_methods_spend_at_most_their_budget(method, budget):
    fun = Counted()
    try:
        result = plateau_free.minimize(fun, X0, method=method, budget=budget)
    except ValueError as e:  # a budget too small for the paper's loop of 'polished'
        assert method == "polished" and "budget" in str(e)
        return
    assert result.nfev == len(fun.points) <= budget


@pytest.mark.parametrize("method", ["adaptive", "polished"])
@pytest.mark.parametrize("seed", range(3))
def test_the_best_point_seen_is_never_worse_than_the_start(method, seed):
    # Every method evaluates x0 and returns the best point seen, so the result is never worse
    # than the start. Here x0 is the minimum: every other point is worse.
    fun = Counted()
    x0 = np.zeros(200)
    result = plateau_free.minimize(lambda x: float(x @ x) + fun(x) * 0.0, x0, method=method, budget=100, seed=seed)
    assert result.fun == 0.0
    np.testing.assert_array_equal(result.x, x0)
    np.testing.assert_array_equal(fun.points[0], x0)  # the start, evaluated first


@pytest.mark.parametrize("method", ["adaptive", "polished", "plateau", "fd", "spsa"])
@pytest.mark.parametrize("seed", range(3))
def test_fun_is_never_called_outside_the_box(method, seed):
    # Bounds are a promise for every method, the paper's loop and method='polished' included:
    # fun is called only inside the box, and the result lies inside it.
    lower, upper = np.array([-1.0, -1.0, -1.0]), np.array([1.0, 1.0, 1.0])
    fun = Counted()
    options = dict(budget=800) if method != "fd" else dict(iterations=60)
    result = plateau_free.minimize(fun, [0.9] * 3, method=method, bounds=[(-1, 1)] * 3, seed=seed, **options)
    points = np.array(fun.points)
    outside = np.sum(np.any((points < lower) | (points > upper), axis=1))
    assert outside == 0, f"{outside} of {len(points)} points outside the box"
    assert np.all(result.x >= lower) and np.all(result.x <= upper)
    if method in ("adaptive", "polished"):
        assert result.fun >= 5.0  # the best value inside the box


@pytest.mark.parametrize("method", ["adaptive", "polished", "plateau"])
def test_ask_tell_never_asks_outside_the_box(method):
    es = plateau_free.ask_tell([0.9] * 3, method=method, budget=600, bounds=[(-1, 1)] * 3, seed=4)
    while not es.done:
        X, _ = es.ask()
        assert np.all(X >= -1.0) and np.all(X <= 1.0)
        es.tell([staircase(x) for x in X])
    assert np.all(np.abs(es.result.x) <= 1.0)
