"""Ask and tell: the run hands out points, you evaluate them where you like and tell the values.

    python python/examples/ask_tell.py

Here a pool of worker processes evaluates each iteration's points (a render farm or a queue
would do the same). With the same options and seed, the result is `minimize`'s, bit for bit.
"""

from concurrent.futures import ProcessPoolExecutor

import numpy as np

import plateau_free


def stairs(x):
    """Flat almost everywhere: the squared distance of the rounded point to (1, -2, 3)."""
    return float(np.sum((np.floor(x + 0.5) - np.array([1.0, -2.0, 3.0])) ** 2))


if __name__ == "__main__":
    run = plateau_free.ask_tell([0.0, 0.0, 0.0], budget=2000, seed=1)
    with ProcessPoolExecutor(max_workers=2) as pool:
        while not run.done:
            X, seeds = run.ask()                  # one iteration's points, and a seed for each
            run.tell(list(pool.map(stairs, X)))   # their values, in the order of X
    result = run.result
    print("ask and tell:", result.x, result.fun, result.nfev)
    same = plateau_free.minimize(stairs, [0.0, 0.0, 0.0], budget=2000, seed=1)
    assert np.array_equal(result.x, same.x) and result.fun == same.fun == 0.0
