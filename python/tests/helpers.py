"""Reference functions shared by the tests."""

import _thread
import contextlib
import math
import threading
import time
import types

import numpy as np
import pytest


def bumpy(x):
    """The same arithmetic, in the same order, as `bumpy` in python/src/lib.rs."""
    total = 0.0
    for i, v in enumerate(x):
        d = float(v) - 0.1 * i
        total += (i + 1.0) * d * d
    if float(x[0]) + 2.0 * float(x[-1]) > 0.3:
        total += 1.0
    return total


def bumpy_seeded(x, seed):
    return bumpy(x) + (seed % 1000) * 1e-3


def phi(z):
    return math.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi)


def tilted_step_gradient(a, b, theta, spreads):
    """grad of E f(theta + tau), tau ~ N(0, diag(spreads)^2), for f(x) = 1[a.x > b]."""
    a = np.asarray(a, dtype=float)
    s = np.sqrt(np.sum(a * a * np.asarray(spreads, dtype=float) ** 2))
    z = (a @ np.asarray(theta, dtype=float) - b) / s
    return a * phi(z) / s


STAIR_TARGET = (1.0, -2.0, 3.0)


def staircase(x):
    """The same arithmetic, in the same order, as `staircase` in python/src/lib.rs: the squared
    distance of the rounded point (floor(v + 0.5)) to the integer target (1, -2, 3, 1, ...)."""
    total = 0.0
    for i, v in enumerate(np.ravel(x)):
        d = math.floor(float(v) + 0.5) - STAIR_TARGET[i % 3]
        total += d * d
    return total


def staircase_seeded(x, seed):
    return staircase(x) + (int(seed) % 1000) * 1e-3


def staircase_batch(xs):
    """`staircase` of every row of a (N, 3) array, vectorised, with the same rounding and the
    same order of additions ((d0^2 + d1^2) + d2^2, as 0.0 + d0^2 is d0^2)."""
    d = np.floor(xs + 0.5) - np.asarray(STAIR_TARGET)
    sq = d * d
    return (sq[:, 0] + sq[:, 1]) + sq[:, 2]


def interrupting(fun, at=5):
    """``fun`` that sends the main thread a KeyboardInterrupt on its ``at``-th call, and the list
    holding its count of calls."""
    count = [0]

    def wrapped(x):
        count[0] += 1
        if count[0] == at:
            _thread.interrupt_main()
        return fun(x)

    return wrapped, count


@contextlib.contextmanager
def interrupted_within(seconds=5.0, after=0.3, again=1.0):
    """Presses Ctrl-C (``_thread.interrupt_main()``) ``after`` seconds in and again every
    ``again`` seconds while the block runs, as a user whose first press went unanswered would:
    CPython drops a KeyboardInterrupt raised while a finalizer or a weakref callback runs (it
    only prints it), so one press can be lost. The block (a run, which Ctrl-C ends with its
    best so far) must end within ``seconds``, and should have a budget that ends it by itself
    if every press were lost. Yields a namespace for the block's result."""
    ended = threading.Event()

    def press():
        wait = after
        while not ended.wait(wait):
            _thread.interrupt_main()
            wait = again

    presser = threading.Thread(target=press, daemon=True)
    start = time.perf_counter()
    presser.start()
    try:
        yield types.SimpleNamespace(result=None)
    finally:
        ended.set()
        presser.join()
    took = time.perf_counter() - start
    assert took < seconds, f"the run took {took:.1f} s after Ctrl-C at {after} s"


def smoothed_step_gradient(theta, a, sigma):
    """d/dtheta E 1[theta + tau > a], tau ~ N(0, sigma^2): phi((theta - a) / sigma) / sigma."""
    return phi((theta - a) / sigma) / sigma


def smoothed_floor_gradient(theta, sigma):
    """d/dtheta E floor(theta + tau), tau ~ N(0, sigma^2): floor jumps by 1 at every integer k,
    so the sum of phi((theta - k) / sigma) / sigma over the integers (those within 40 sigma)."""
    reach = int(math.ceil(40 * sigma)) + 1
    centre = int(math.floor(theta))
    return sum(smoothed_step_gradient(theta, k, sigma) for k in range(centre - reach, centre + reach + 1))


def floor_sum(x):
    """The staircase sum(floor(x)): flat between integers, a jump of 1 at each."""
    return float(np.sum(np.floor(x)))


def assert_mean_matches(samples, expected, what, sigmas=4.0):
    """The mean of ``samples`` (one row per key or seed) is ``expected`` within ``sigmas``
    standard errors of that mean, computed from the samples; the standard error must be small
    enough (a tenth of the largest |expected|, or 1e-3) for the test to mean something."""
    samples = np.asarray(samples, dtype=float)
    mean = samples.mean(axis=0)
    se = samples.std(axis=0, ddof=1) / math.sqrt(len(samples))
    expected = np.asarray(expected, dtype=float)
    assert np.all(se < max(0.1 * np.max(np.abs(expected)), 1e-3)), f"{what}: standard error {se} too large"
    assert np.all(np.abs(mean - expected) <= sigmas * se + 1e-12), (
        f"{what}: mean {mean} vs analytic {expected}, standard error {se} ({len(samples)} samples)"
    )
