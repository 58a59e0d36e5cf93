"""Reference functions shared by the tests."""

import math

import numpy as np


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
