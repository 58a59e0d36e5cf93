"""One estimator (or Adam, or an ask/tell run) shared by threads works: the calls run
one at a time, each with its own shape and its own exception, and no thread waits for the lock
while holding the GIL (the holder needs it to call ``fun``)."""

import threading
import time

import numpy as np
import pytest

import plateau_free

THREADS = 4
EACH = 6


def slow_quadratic(x):
    time.sleep(0.0005)  # releases the GIL: the threads interleave inside the estimates
    return float(np.sum((x - 0.3) ** 2))


def run_threads(work, count=THREADS):
    """``work(k)`` on ``count`` threads at once; their results and exceptions, by thread."""
    results = [None] * count
    errors = [None] * count
    start = threading.Barrier(count)

    def body(k):
        start.wait()
        try:
            results[k] = work(k)
        except BaseException as e:  # noqa: BLE001 - reported below
            errors[k] = e

    threads = [threading.Thread(target=body, args=(k,)) for k in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert not any(t.is_alive() for t in threads), "a thread hangs: deadlock"
    return results, errors


MAKERS = {
    "PlateauFreeGradient": lambda: plateau_free.PlateauFreeGradient(slow_quadratic, samples=4, seed=3),
    "PlateauFreeGradient-batched": lambda: plateau_free.PlateauFreeGradient(
        lambda X: np.array([slow_quadratic(x) for x in X]), samples=4, seed=3, batched=True
    ),
    "PlateauFreeGradient-parallel": lambda: plateau_free.PlateauFreeGradient(
        slow_quadratic, samples=4, seed=3, parallel=True
    ),
    "FiniteDifference": lambda: plateau_free.FiniteDifference(slow_quadratic),
    "Spsa": lambda: plateau_free.Spsa(slow_quadratic, seed=3),
}


@pytest.mark.parametrize("kind", sorted(MAKERS))
def test_one_estimator_shared_by_four_threads(kind):
    # Every thread gets its answer: none fails with RuntimeError: Already borrowed.
    x = np.array([0.1, -0.2, 0.5])
    shared = MAKERS[kind]()
    results, errors = run_threads(lambda k: [shared.estimate(x, 0.4) for _ in range(EACH)])
    assert errors == [None] * THREADS
    got = [g for per_thread in results for g in per_thread]
    assert len(got) == THREADS * EACH and all(np.all(np.isfinite(g)) for g in got)
    # Each estimate draws the numbers of its place in the order the threads got the lock: the
    # set of results is that of the same number of estimates in a row.
    alone = MAKERS[kind]()
    expected = [alone.estimate(x, 0.4) for _ in range(THREADS * EACH)]
    assert sorted(g.tobytes() for g in got) == sorted(g.tobytes() for g in expected)
    if hasattr(shared, "estimates"):
        assert shared.estimates == THREADS * EACH
    assert shared.nfev == alone.nfev


def test_each_thread_gets_its_own_shape_and_its_own_exception():
    class Negative(Exception):
        pass

    def fun(x):
        time.sleep(0.0002)
        if np.ravel(x)[0] < -5:
            raise Negative(f"x[0] = {np.ravel(x)[0]}")
        return float(np.sum(x))

    shared = plateau_free.PlateauFreeGradient(fun, samples=6, seed=1)
    starts = [np.zeros(4), np.zeros((2, 2)), np.full(4, -10.0), np.zeros((1, 4))]

    def work(k):
        return [shared.estimate(starts[k], 0.01) for _ in range(EACH)]

    results, errors = run_threads(work)
    assert isinstance(errors[2], Negative) and results[2] is None
    for k in (0, 1, 3):
        assert errors[k] is None
        assert all(g.shape == starts[k].shape for g in results[k])
    # The estimator is still usable.
    assert shared.estimate(np.zeros(4), 0.01).shape == (4,)


def test_adam_and_ask_tell_shared_by_threads():
    adam = plateau_free.Adam(0.01)
    results, errors = run_threads(lambda k: [adam.step(np.zeros(3), np.ones(3)) for _ in range(50)])
    assert errors == [None] * THREADS and adam.steps == THREADS * 50

    # One thread asks and tells (an ask and its tell belong together); the others read.
    es = plateau_free.ask_tell([0.0, 0.0, 0.0], budget=400, seed=1)

    def work(k):
        if k == 0:
            while not es.done:
                X, _ = es.ask()
                es.tell([float(np.sum(x**2)) for x in X])
            return es.nfev
        reads = 0
        while not es.done:
            _ = (es.nfev, es.best, repr(es))
            reads += 1
            time.sleep(0.0001)
        return reads

    results, errors = run_threads(work)
    assert errors == [None] * THREADS
    assert es.result.nfev == results[0] <= 400


def test_a_call_from_inside_a_call_is_refused_not_a_hang():
    # fun using the estimator that is evaluating it would wait for itself forever.
    box = {}

    def fun(x):
        box["grad"].estimate(x, 0.1)
        return 0.0

    box["grad"] = plateau_free.PlateauFreeGradient(fun)
    with pytest.raises(RuntimeError, match="in use by this very thread"):
        box["grad"].estimate([0.0], 0.1)
    assert plateau_free.PlateauFreeGradient(lambda x: 0.0).estimate([0.0], 0.1).shape == (1,)
