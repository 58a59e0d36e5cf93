"""Callbacks as scipy's (a true value returned or StopIteration raised stops the run,
and the result comes back), and ``success``/``status`` with scipy's meaning."""

import numpy as np
import pytest

import plateau_free
from helpers import staircase

X0 = [0.0, 0.0, 0.0]
METHODS = {
    "adaptive": dict(budget=2000),
    "polished": dict(budget=2000),
    "plateau": dict(iterations=100),
    "fd": dict(iterations=100),
    "spsa": dict(iterations=100),
}


class Recorder:
    """A callback that records what it sees and, at iteration ``at``, answers ``answer`` (or
    raises it, if it is an exception)."""

    def __init__(self, at, answer):
        self.at, self.answer, self.seen = at, answer, []

    def __call__(self, intermediate_result):
        self.seen.append(intermediate_result)
        if intermediate_result.nit == self.at:
            if isinstance(self.answer, BaseException) or self.answer is StopIteration:
                raise self.answer
            return self.answer
        return None


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("answer", [True, np.True_, 1, "stop", [0]], ids=repr)
def test_a_true_value_returned_stops_the_run(method, answer):
    # Any true value stops the run, numpy's np.True_ and 1 included, as in scipy.
    callback = Recorder(3, answer)
    result = plateau_free.minimize(staircase, X0, method=method, callback=callback, seed=1, **METHODS[method])
    assert result.nit == 3 and len(callback.seen) == 3
    assert not result.success and result.status == 99
    assert result.message == "stopped by the callback (it returned a true value) after iteration 3"
    assert result.nfev == callback.seen[-1].nfev + (method in ("plateau", "fd", "spsa"))  # + the final evaluation


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("answer", [None, False, np.False_, 0, ""], ids=repr)
def test_a_false_value_goes_on(method, answer):
    callback = Recorder(3, answer)
    result = plateau_free.minimize(staircase, X0, method=method, callback=callback, **METHODS[method])
    assert result.nit > 3 and result.status != 99


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("raised", [StopIteration, StopIteration("enough")], ids=repr)
def test_stop_iteration_ends_the_run_and_returns_the_result(method, raised):
    # StopIteration is scipy's way to stop: it ends the run, and the result is returned.
    callback = Recorder(4, raised)
    result = plateau_free.minimize(staircase, X0, method=method, callback=callback, seed=2, **METHODS[method])
    assert result.nit == 4 and len(callback.seen) == 4
    assert not result.success and result.status == 99
    assert result.message == "`callback` raised `StopIteration`."  # scipy's words
    last = callback.seen[-1]
    np.testing.assert_array_equal(result.x, last.x)
    if method in ("adaptive", "polished"):  # the best point so far
        assert result.fun == last.fun == min(r.fun for r in callback.seen)
        assert result.fun == staircase(result.x)
    else:  # the current iterate, evaluated once more
        assert result.fun == staircase(result.x)
        assert result.history is not None and len(result.history) == 4


@pytest.mark.parametrize("method", ["adaptive", "plateau"])
def test_stop_iteration_with_a_plain_callback(method):
    def callback(x):
        raise StopIteration

    result = plateau_free.minimize(staircase, X0, method=method, callback=callback, **METHODS[method])
    assert result.nit == 1 and result.status == 99 and not result.success


def test_a_callback_answer_without_a_truth_value_is_a_value_error():
    with pytest.raises(ValueError, match="callback returned array.*neither true nor false"):
        plateau_free.minimize(staircase, X0, callback=lambda x: np.array([1, 0]), budget=100)


def test_other_exceptions_of_the_callback_come_out_unchanged():
    class Boom(Exception):
        pass

    def callback(x):
        raise Boom("from the callback")

    for method in METHODS:
        with pytest.raises(Boom, match="from the callback"):
            plateau_free.minimize(staircase, X0, method=method, callback=callback, **METHODS[method])


def test_success_and_status_follow_scipy():
    # success is False when the budget runs out far from any minimum, as in scipy.
    spent = plateau_free.minimize(lambda x: float(np.sum(x**2)), np.full(5, 3.0), budget=60)
    assert not spent.success and spent.status == 1
    assert spent.message == "budget spent: 60 of at most 60 evaluations; x is the best point seen"
    default = plateau_free.minimize(lambda x: float(np.sum(np.abs(x))) + 1.0, [3.0], patience=0)
    assert not default.success and default.status == 1 and "of at most 1000 evaluations" in default.message
    # The default: restarts that converge back at the best point end the run, a success.
    done = plateau_free.minimize(lambda x: float(np.sum(np.abs(x))) + 1.0, [3.0])
    assert done.success and done.status == 0 and done.message.startswith("done") and done.nfev < 1000
    target = plateau_free.minimize(staircase, X0, budget=5000, target=0.0)
    assert target.success and target.status == 0 and target.message == "target reached"
    converged = plateau_free.minimize(lambda x: float(x @ x), [1.0, 1.0], budget=10**5, restarts=False)
    assert converged.success and converged.status == 0 and converged.message == "converged"
    for method in ("plateau", "fd", "spsa"):  # the paper's loop never tests for convergence
        done = plateau_free.minimize(staircase, X0, method=method, iterations=20)
        assert not done.success and done.status == 1
        assert done.message.startswith("completed 20 iterations (the iteration limit")
    es = plateau_free.ask_tell(X0, budget=50)
    while not es.done:
        X, _ = es.ask()
        es.tell([staircase(x) for x in X])
    assert not es.result.success and es.result.status == 1
    es = plateau_free.ask_tell(X0, method="plateau", iterations=5)
    while not es.done:
        X, _ = es.ask()
        es.tell([staircase(x) for x in X])
    assert not es.result.success and es.result.status == 1
