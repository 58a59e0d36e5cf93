"""plateau_free.scipy.method: scipy.optimize.minimize(f, x0, method=plateau_free.scipy.method,
options={"maxfev": budget, "seed": s, ...}) is plateau_free.minimize(f, x0, budget=budget,
seed=s, ...), bit for bit, in a scipy OptimizeResult. scipy is a test requirement
(python/requirements-test.txt): these tests fail, never skip, when it is missing."""

from __future__ import annotations

import doctest

import numpy as np
import pytest
import scipy.optimize

import plateau_free
import plateau_free.scipy
from helpers import staircase


def run(fun, x0, **kwargs):
    return scipy.optimize.minimize(fun, x0, method=plateau_free.scipy.method, **kwargs)


@pytest.mark.parametrize(
    "options",
    [
        {"maxfev": 600, "seed": 3},
        {"maxfev": 900, "seed": 4, "target": 0.0},
        {"maxfev": 800, "seed": 5, "method": "plateau", "samples": 4},
        {"maxfev": 800, "seed": 6, "method": "polished", "polish": 0.5},
    ],
)
def test_the_result_is_minimizes_bit_for_bit_in_a_scipy_result(options):
    x0 = [2.7, 0.4, -1.3]
    res = run(staircase, x0, options=options)
    ours = {("budget" if k == "maxfev" else k): v for k, v in options.items()}
    expected = plateau_free.minimize(staircase, x0, **ours)
    assert isinstance(res, scipy.optimize.OptimizeResult)
    for name in ("fun", "nit", "nfev", "success", "status", "message"):
        assert res[name] == expected[name], name
    assert np.array_equal(res.x, expected.x)
    assert res.nfev <= options["maxfev"]


def test_the_search_finds_the_staircases_minimum():
    res = run(staircase, [2.7, 0.4, -1.3], options={"maxfev": 2000, "seed": 0, "target": 0.0})
    assert res.success and res.fun == 0.0 and res.nfev <= 2000
    assert np.array_equal(np.floor(res.x + 0.5), [1.0, -2.0, 3.0])


def test_args_bounds_and_callback_are_scipys():
    seen = []

    def fun(x, shift, scale):
        return scale * float(np.sum(np.floor(x - shift) ** 2))

    bounds = scipy.optimize.Bounds([-3.0, -3.0], [3.0, 3.0])
    res = run(fun, [2.5, -2.5], args=(0.5, 2.0), bounds=bounds, callback=seen.append, options={"maxfev": 500})
    expected = plateau_free.minimize(lambda x: fun(x, 0.5, 2.0), [2.5, -2.5], budget=500, bounds=bounds)
    assert np.array_equal(res.x, expected.x) and res.fun == expected.fun
    assert len(seen) == res.nit and all(np.all(np.abs(x) <= 3.0) for x in seen)
    # Pairs, scipy's other spelling of bounds.
    paired = run(fun, [2.5, -2.5], args=(0.5, 2.0), bounds=[(-3, 3), (-3, 3)], options={"maxfev": 500})
    assert np.array_equal(paired.x, expected.x)


def test_a_callback_that_returns_true_stops_the_run():
    def stop(intermediate_result):
        return intermediate_result.nfev >= 50

    res = run(staircase, [2.7, 0.4, -1.3], callback=stop, options={"maxfev": 1000})
    assert not res.success and res.status == 99 and 50 <= res.nfev < 1000


def test_derivatives_are_not_used_and_say_so():
    with pytest.warns(RuntimeWarning, match="jac"):
        res = run(staircase, [2.7, 0.4, -1.3], jac=lambda x: np.zeros(3), options={"maxfev": 200})
    assert res.nfev <= 200


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"options": {"maxfev": 0}}, "budget"),
        ({"options": {"maxfev": -5}}, "budget"),
        ({"options": {"seed": -1}}, "seed"),
        ({"options": {"budget": 100}}, "budget = 100: give scipy's name"),
        ({"options": {"samples": 4}}, "samples"),
        ({"options": {"lr": 0.1}}, "lr"),
        ({"options": {"popsize": 10}}, "popsize"),
        ({"options": {"method": "bfgs"}}, "method"),
        ({"tol": 1e-6}, "tol"),
        ({"constraints": [{"type": "ineq", "fun": lambda x: x[0]}]}, "constraints"),
    ],
)
def test_bad_options_are_value_errors_naming_them(kwargs, name):
    with pytest.raises(ValueError, match=name):
        run(staircase, [2.7, 0.4, -1.3], **kwargs)


def test_the_modules_example_runs():
    failures, tried = doctest.testmod(plateau_free.scipy, optionflags=doctest.ELLIPSIS)
    assert tried > 0 and failures == 0
