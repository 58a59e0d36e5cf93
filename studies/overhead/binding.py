"""The cost of the binding per evaluation of a trivial Python objective.

    python -m studies overhead            # after pip install ./python

Per evaluation, an estimate with an unbatched ``fun`` re-acquires the GIL, checks for signals,
builds one numpy array for the point, calls ``fun`` and reads a float. The overhead is the time
per evaluation of ``PlateauFreeGradient(fun).estimate`` minus the time of the call itself,
measured as ``fun`` mapped over ready-made arrays from C (``deque(map(fun, arrays))``), so
that no Python loop is counted on either side. The Rust estimator's own work per evaluation
(drawing the perturbation, the weighted sum), measured on a Rust closure, is part of the
overhead and shown on its own.

The batched path hands ``fun`` all points of an estimate as one ``(N, n)`` array, made by one
copy of the Rust buffer; its cost per point is compared with ``X.copy()`` of the same array.
"""

from __future__ import annotations

import argparse
import collections
import time

import numpy as np

import plateau_free
from plateau_free import _native


def best_of(repeats: int, run) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def unbatched(dim: int, samples: int, repeats: int) -> dict[str, float]:
    def fun(x):
        return 0.0

    x = np.full(dim, 0.5)
    arrays = [np.zeros(dim) for _ in range(samples)]
    call = best_of(repeats, lambda: collections.deque(map(fun, arrays), maxlen=0)) / samples
    make = best_of(repeats, lambda: [np.array(x) for _ in range(samples)]) / samples
    grad = plateau_free.PlateauFreeGradient(fun, samples=samples)
    estimate = best_of(repeats, lambda: grad.estimate(x, 0.1)) / samples
    rust = _native._rust_seconds_per_evaluation(dim=dim, samples=samples, repeats=repeats)
    return dict(call=call, make=make, estimate=estimate, overhead=estimate - call, rust=rust)


def batched(dim: int, samples: int, repeats: int) -> dict[str, float]:
    def fun(X):
        return np.zeros(len(X))

    x = np.full(dim, 0.5)
    X = np.zeros((samples, dim))
    call = best_of(repeats, lambda: fun(X))
    copy = best_of(repeats, lambda: X.copy())
    grad = plateau_free.PlateauFreeGradient(fun, samples=samples, batched=True)
    estimate = best_of(repeats, lambda: grad.estimate(x, 0.1))
    rust = _native._rust_seconds_per_evaluation(dim=dim, samples=samples, repeats=repeats) * samples
    return dict(call=call, copy=copy, estimate=estimate, overhead=estimate - call, rust=rust)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20_000, help="evaluations per estimate")
    parser.add_argument("--repeats", type=int, default=7, help="best of this many runs")
    args = parser.parse_args()
    us = 1e6

    print(f"Unbatched fun(x) -> 0.0: {args.samples} evaluations per estimate, best of {args.repeats}; microseconds per evaluation")
    print(f"{'n':>6} | {'fun call':>8} | {'estimate':>8} | {'Rust estimator alone':>20} | {'binding overhead':>16}")
    print("-" * 72)
    for dim in [1, 10, 100, 1000]:
        r = unbatched(dim, args.samples, args.repeats)
        binding = r["estimate"] - r["call"] - r["rust"]
        print(f"{dim:>6} | {r['call'] * us:>8.3f} | {r['estimate'] * us:>8.3f} | {r['rust'] * us:>20.3f} | {binding * us:>16.3f}")
    print("binding overhead = estimate - fun call - Rust estimator alone (GIL, signal check, the point's array, the call's arguments, reading the float)")

    print()
    print(f"Batched fun(X) -> zeros(N): N = {args.samples} points per estimate, best of {args.repeats}; nanoseconds per point")
    print(f"{'n':>6} | {'fun call':>8} | {'estimate':>8} | {'Rust estimator alone':>20} | {'binding overhead':>16} | {'X.copy()':>8}")
    print("-" * 83)
    per = 1e9 / args.samples
    for dim in [1, 10, 100, 1000]:
        r = batched(dim, args.samples, args.repeats)
        binding = r["estimate"] - r["call"] - r["rust"]
        print(
            f"{dim:>6} | {r['call'] * per:>8.1f} | {r['estimate'] * per:>8.1f} | {r['rust'] * per:>20.1f} | {binding * per:>16.1f} | {r['copy'] * per:>8.1f}"
        )
    print("X.copy(): numpy copying an array of the same shape, for scale (the binding makes X with one such copy)")


if __name__ == "__main__":
    main()
