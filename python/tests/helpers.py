"""Reference functions shared by the tests."""

import _thread
import contextlib
import math
import threading
import time

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
def interrupted_within(seconds=5.0, after=0.3):
    """Interrupts the main thread ``after`` seconds in; the block must end in KeyboardInterrupt
    within ``seconds``."""
    timer = threading.Timer(after, _thread.interrupt_main)
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            yield
    finally:
        timer.cancel()
    assert time.perf_counter() - start < seconds
