"""`minimize(fun, x0, budget=...)`: the Rust `plateau_free::Minimizer` (method 'adaptive')."""

import math

import numpy as np
import pytest

import plateau_free
from plateau_free import _native
from helpers import (
    interrupted_within,
    interrupting,
    staircase,
    staircase_batch,
    staircase_seeded,
)

X0 = [0.0, 0.0, 0.0]  # staircase(X0) = 1 + 4 + 9 = 14


def same(result, rust):
    assert result.x.tobytes() == rust["x"].tobytes()
    assert result.fun == rust["fun"]
    assert result.nfev == rust["nfev"]
    assert result.nit == rust["nit"]
    assert result.restarts == rust["restarts"]
    assert result.sigma == rust["sigma"]
    assert result.message.startswith(rust["stop"])


def test_staircase_solved_with_defaults():
    assert staircase(X0) == 14.0
    result = plateau_free.minimize(staircase, X0, budget=2000, patience=0)
    assert result.fun == 0.0
    assert np.array_equal(np.floor(result.x + 0.5), [1.0, -2.0, 3.0])
    assert staircase(result.x) == 0.0
    assert result.nfev <= 2000
    # Without the done rule the budget runs out: scipy's "maximum number of evaluations", not
    # a success.
    assert not result.success and result.status == 1
    assert result.message == "budget spent: 2000 of at most 2000 evaluations; x is the best point seen"
    assert isinstance(result.history, plateau_free.SearchHistory)
    assert result.history.nfev[-1] == result.nfev and result.history.fun[-1] == 0.0
    # With it (the default), the run is done well before its budget.
    done = plateau_free.minimize(staircase, X0, budget=2000)
    assert done.fun == 0.0 and done.success and done.status == 0 and done.nfev < 2000
    assert isinstance(result.restarts, int) and result.sigma > 0.0
    assert result.x.shape == (3,)


@pytest.mark.parametrize("seed", [0, 1, 12345])
def test_bit_identical_to_the_rust_minimizer(seed):
    rust = _native._rust_reference_minimize_adaptive(X0, budget=1500, seed=seed)
    same(plateau_free.minimize(staircase, X0, budget=1500, seed=seed), rust)
    # The explicit method, and a batched fun (one call per iteration): the same numbers.
    same(plateau_free.minimize(staircase, X0, budget=1500, seed=seed, method="adaptive"), rust)
    same(plateau_free.minimize(staircase_batch, X0, budget=1500, seed=seed, batched=True), rust)


def test_seeded_bounds_sigma0_bit_identical():
    bounds = ([-4.0, -4.0, -4.0], [4.0, 4.0, 4.0])
    rust = _native._rust_reference_minimize_adaptive(X0, budget=900, seed=7, sigma0=0.8, bounds=bounds, seeded=True)
    seeds = []

    def fun(x, seed):
        seeds.append(int(seed))
        return staircase_seeded(x, seed)

    result = plateau_free.minimize(
        fun, X0, budget=900, seed=7, sigma0=0.8, bounds=[(-4.0, 4.0)] * 3, seeded=True, method="adaptive"
    )
    same(result, rust)
    assert len(set(seeds)) == result.nit  # one seed per iteration (common random numbers)

    def fun_batch(xs, seeds):
        assert xs.ndim == 2 and seeds.dtype == np.uint64 and len(set(seeds.tolist())) == 1
        return staircase_batch(xs) + (seeds % np.uint64(1000)).astype(float) * 1e-3

    batched = plateau_free.minimize(
        fun_batch, X0, budget=900, seed=7, sigma0=0.8, bounds=(-4.0, 4.0), seeded=True, batched=True, method="adaptive"
    )
    same(batched, rust)


def long_axes_ellipsoid(n):
    """The ellipsoid of the Rust test ``tests/low_rank.rs``: condition 1e4, its three long
    axes dense unit vectors (no coordinate axis among them), batched."""
    axes = []
    for k in range(3):
        v = np.array([((i * (2 * k + 3) + k) % 17) - 8.0 for i in range(n)])
        for a in axes:
            v -= (v @ a) * a
        axes.append(v / np.linalg.norm(v))
    a = np.array(axes)

    def f(xs):
        along = ((xs @ a.T) ** 2).sum(axis=1)
        return 1e4 * ((xs * xs).sum(axis=1) - along) + along

    return f, 1.0 + ((np.arange(n) * 7) % 11) / 11.0


def test_metric_auto_is_full_up_to_19_decoded_up_to_200_and_diagonal_above():
    other_of = {"full": "decoded", "decoded": "full", "diagonal": "low_rank"}
    for n, same_as in [(6, "full"), (19, "full"), (20, "decoded"), (200, "decoded"), (201, "diagonal")]:
        f, x0 = long_axes_ellipsoid(n)
        runs = [plateau_free.minimize(f, x0, budget=3000, seed=1, batched=True, metric=m) for m in ("auto", same_as)]
        assert np.array_equal(runs[0].x, runs[1].x) and runs[0].fun == runs[1].fun
        other = other_of[same_as]
        assert plateau_free.minimize(f, x0, budget=3000, seed=1, batched=True, metric=other).fun != runs[0].fun


def test_metric_low_rank_learns_a_rotated_ellipsoid_the_diagonal_does_not():
    # As tests/low_rank.rs: n = 500, 200,000 evaluations (the directions need about 10^5 to
    # grow); there the diagonal ends near 8 and the low rank near 0.01.
    f, x0 = long_axes_ellipsoid(500)
    diagonal, low_rank = (
        plateau_free.minimize(f, x0, budget=200_000, seed=0, batched=True, metric=m) for m in ("diagonal", "low_rank")
    )
    assert low_rank.fun < diagonal.fun / 20.0
    asked = plateau_free.ask_tell(x0, budget=200_000, seed=0, metric="lowrank")
    while not asked.done:
        xs, _ = asked.ask()
        asked.tell(f(xs))
    assert asked.result.fun == low_rank.fun


def test_batched_is_called_once_per_iteration():
    calls = []

    def fun(xs):
        calls.append(xs.shape)
        return staircase_batch(xs)

    result = plateau_free.minimize(fun, X0, budget=500, batched=True)
    assert calls[0] == (1, 3)  # the start, evaluated first and alone
    assert len(calls) == result.nit + 1
    assert sum(c[0] for c in calls) == result.nfev
    assert all(len(c) == 2 and c[1] == 3 for c in calls)


def test_x_keeps_its_shape():
    def fun(x):
        assert x.shape == (1, 3)
        return staircase(x)

    result = plateau_free.minimize(fun, [X0], budget=600)
    assert result.x.shape == (1, 3)


def test_target_and_restarts():
    result = plateau_free.minimize(staircase, X0, budget=5000, target=0.0)
    assert result.fun == 0.0 and result.status == 0 and result.success and result.message == "target reached"
    assert result.nfev < 5000
    off = plateau_free.minimize(lambda x: float(np.sum(x * x)), [1.0, 1.0], budget=100000, restarts=False)
    assert off.message == "converged" and off.status == 0 and off.success and off.restarts == 0
    assert off.nfev < 100000


def test_callback_sees_the_best_and_can_stop():
    seen = []

    def callback(intermediate_result):
        seen.append((intermediate_result.nit, intermediate_result.fun, intermediate_result.nfev))
        return intermediate_result.nit == 5

    result = plateau_free.minimize(staircase, X0, budget=2000, callback=callback)
    assert result.nit == 5 and result.status == 99 and not result.success and "callback" in result.message
    assert [s[0] for s in seen] == [1, 2, 3, 4, 5]
    assert [s[1] for s in seen] == sorted((s[1] for s in seen), reverse=True)
    assert result.fun == seen[-1][1] == staircase(result.x)
    assert result.nfev == seen[-1][2]
    assert result.restarts is None and result.sigma is None

    xs = []
    plateau_free.minimize(staircase, X0, budget=200, callback=lambda x: xs.append(x.copy()))
    assert len(xs) > 0 and all(x.shape == (3,) for x in xs)


def test_the_paper_loop_is_chosen_by_method_alone():
    paper = plateau_free.minimize(staircase, X0, budget=400, method="plateau")
    assert "restarts" not in paper and paper.history is not None and paper.nit == 199
    assert plateau_free.minimize(staircase, X0, budget=400, samples=4, method="plateau").nit == 99
    assert len(plateau_free.minimize(staircase, X0, iterations=10, method="plateau").history) == 10
    # An option of the paper's loop never selects it: with the default method it is an error.
    for option in (dict(sigma0=0.5, iterations=10), dict(samples=4), dict(iterations=10), dict(lr=0.1)):
        name = [k for k in option if k != "sigma0"][0]
        with pytest.raises(ValueError, match=f"{name} = .*: not an option of method='adaptive' .the default method."):
            plateau_free.minimize(staircase, X0, **option)


@pytest.mark.parametrize("budget", [0, -3])
def test_bad_budget(budget):
    with pytest.raises(ValueError, match=f"budget = {budget}"):
        plateau_free.minimize(staircase, X0, budget=budget)


def test_bad_x0():
    with pytest.raises(ValueError, match=r"x0\[1\] = nan"):
        plateau_free.minimize(staircase, [0.0, math.nan, 0.0], budget=100)
    with pytest.raises(ValueError, match=r"x0\[0\] = inf"):
        plateau_free.minimize(staircase, [math.inf, 0.0, 0.0], budget=100)


def test_bad_bounds():
    with pytest.raises(ValueError, match=r"bounds\[1\] = \(2, 1\): lower 2 > upper 1"):
        plateau_free.minimize(staircase, X0, budget=100, bounds=[(-1, 1), (2, 1), (-1, 1)])
    with pytest.raises(ValueError, match=r"x0\[0\] = 0\.0 is outside bounds\[0\] = \(1, 2\)"):
        plateau_free.minimize(staircase, X0, budget=100, bounds=[(1, 2)] * 3)
    with pytest.raises(ValueError, match=r"bounds\[0\] = \(None, 1, 2\) must be a \(lower, upper\) pair"):
        plateau_free.minimize(staircase, X0, budget=100, bounds=[(None, 1, 2)] * 3)


def test_bad_options():
    with pytest.raises(ValueError, match="sigma0 = -1.0 is invalid: must be finite and > 0"):
        plateau_free.minimize(staircase, X0, budget=100, sigma0=-1.0, method="adaptive")
    with pytest.raises(ValueError, match="population = 1 is invalid: must be at least 2"):
        plateau_free.minimize(staircase, X0, budget=100, population=1)
    with pytest.raises(
        ValueError,
        match=r"lr = 0.1: not an option of method='adaptive' \(the default method\), an option of method='plateau', 'polished', 'fd' or 'spsa'; "
        r"samples = 4: not an option of method='adaptive' \(the default method\), an option of method='plateau' or 'polished'",
    ):
        plateau_free.minimize(staircase, X0, budget=100, lr=0.1, samples=4, method="adaptive")


def test_non_finite_value_is_a_value_error_under_raise():
    with pytest.raises(ValueError, match="f returned NaN at evaluation 0"):
        plateau_free.minimize(lambda x: math.nan, X0, budget=100, on_failure="raise")
    with pytest.raises(ValueError, match="f returned inf") as info:
        plateau_free.minimize(lambda x: math.inf if x[0] > 0.1 else 1.0, X0, budget=100, on_failure="raise")
    assert info.value.result.fun == 1.0  # the best point so far comes with the error


class Boom(Exception):
    pass


def test_exception_from_fun_propagates_unchanged():
    calls = []
    err = Boom("from fun")

    def fun(x):
        calls.append(1)
        if len(calls) == 7:
            raise err
        return staircase(x)

    with pytest.raises(Boom) as info:
        plateau_free.minimize(fun, X0, budget=1000, on_failure="raise")
    assert info.value is err
    assert len(calls) == 7  # nothing evaluated after the exception
    assert info.value.result.nfev == 1 and info.value.result.status == 3  # the start, told

    def batch(xs):
        raise err

    # Every evaluation raised: the run has nothing to go on with, and raises the first.
    with pytest.raises(Boom) as info:
        plateau_free.minimize(batch, X0, budget=1000, batched=True)
    assert info.value is err


def test_exception_from_callback_propagates():
    def callback(x):
        raise Boom("from callback")

    with pytest.raises(Boom, match="from callback"):
        plateau_free.minimize(staircase, X0, budget=1000, callback=callback)


def test_non_number_is_a_type_error():
    with pytest.raises(TypeError, match="fun must return a real number"):
        plateau_free.minimize(lambda x: "a", X0, budget=100)


def test_keyboard_interrupt_stops_the_adaptive_run_within_one_call():
    fun, count = interrupting(staircase)
    result = plateau_free.minimize(fun, X0, budget=10**6)
    assert count[0] <= 6
    assert result.status == 2 and not result.success and result.message.startswith("interrupted")
    assert result.fun == min(staircase(X0), result.fun) and result.nfev < count[0]

    # `sum` runs no bytecode: the driver sees the signal between calls. The budget (about 30 s
    # of `sum`) ends the run should every press be lost.
    with interrupted_within(5.0) as run:
        run.result = plateau_free.minimize(sum, [0.5, 0.5], budget=2 * 10**7, bounds=(-1.0, 1.0), patience=0)
    assert run.result.status == 2
