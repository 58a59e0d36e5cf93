"""What the framework adapters cost over calling the library directly.

    target/venv/bin/python -m studies adapters     # after scripts/test-all (or pip install "./python[jax,torch,scipy]")

A trivial objective (``f(x) = 0.0``, or ``f(X) = zeros(N)`` batched), so that only the
machinery is timed; best of ``--repeats`` runs of ``--calls`` calls each, microseconds per call.

- JAX: ``jax.jit(jax.grad(g))(theta, key)`` for ``g = plateau_free.jax.wrap(f, ...)`` (float64,
  one host callback for ``f(theta)`` and one for the estimate), against the same estimate made
  directly, ``PlateauFreeGradient(f, seed=s, ...).estimate(theta, sigma)``.
- PyTorch: ``torch.autograd.grad(g(theta, seed), theta)`` against the same direct estimate.
- scipy: ``scipy.optimize.minimize(f, x0, method=plateau_free.scipy.method, options={"maxfev":
  B})`` against ``plateau_free.minimize(f, x0, budget=B)``: microseconds per run, the median of
  ``4 * repeats`` runs of each, alternating.

The direct column already includes making the estimator (as the adapters do, one per call, with
the call's seed) and the ``samples`` evaluations of ``f``.
"""

from __future__ import annotations

import argparse
import time
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize
import torch

import plateau_free
import plateau_free.jax
import plateau_free.scipy
import plateau_free.torch

jax.config.update("jax_enable_x64", True)


def best_of(repeats: int, calls: int, run: Callable[[], object]) -> float:
    """Seconds per call, the best of `repeats` timings of `calls` calls."""
    run()  # compile, warm caches
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            run()
        best = min(best, (time.perf_counter() - start) / calls)
    return best


def objective(batched: bool) -> Callable[[np.ndarray], object]:
    if batched:
        return lambda xs: np.zeros(len(xs))
    return lambda x: 0.0


def direct(dim: int, samples: int, batched: bool, repeats: int, calls: int) -> float:
    f, x = objective(batched), np.zeros(dim)
    return best_of(
        repeats,
        calls,
        lambda: plateau_free.PlateauFreeGradient(f, samples=samples, seed=1, batched=batched).estimate(x, 0.1),
    )


def through_jax(dim: int, samples: int, batched: bool, repeats: int, calls: int) -> float:
    g = plateau_free.jax.wrap(objective(batched), sigma=0.1, samples=samples, batched=batched)
    grad, theta, key = jax.jit(jax.grad(g)), jnp.zeros(dim), jax.random.key(1)
    return best_of(repeats, calls, lambda: grad(theta, key).block_until_ready())


def through_torch(dim: int, samples: int, batched: bool, repeats: int, calls: int) -> float:
    g = plateau_free.torch.wrap(objective(batched), sigma=0.1, samples=samples, batched=batched)
    theta = torch.zeros(dim, dtype=torch.float64, requires_grad=True)
    return best_of(repeats, calls, lambda: torch.autograd.grad(g(theta, 1), theta))


def gradients(args: argparse.Namespace) -> None:
    us = 1e6
    print(f"Gradient of f(x) = 0 (one estimate), best of {args.repeats} x {args.calls} calls; microseconds per call")
    header = f"{'n':>5} | {'samples':>7} | {'batched':>7} | {'direct':>8} | {'JAX (jit)':>9} | {'+ JAX':>8} | {'PyTorch':>8} | {'+ PyTorch':>9}"
    print(header)
    print("-" * len(header))
    for dim, samples, batched in [(1, 2, False), (10, 2, False), (100, 2, False), (10, 64, False), (10, 64, True), (1000, 64, True)]:
        base = direct(dim, samples, batched, args.repeats, args.calls)
        jx = through_jax(dim, samples, batched, args.repeats, args.calls)
        th = through_torch(dim, samples, batched, args.repeats, args.calls)
        print(
            f"{dim:>5} | {samples:>7} | {str(batched):>7} | {base * us:>8.1f} | {jx * us:>9.1f} | {(jx - base) * us:>8.1f}"
            f" | {th * us:>8.1f} | {(th - base) * us:>9.1f}"
        )
    print("+ JAX, + PyTorch: the adapter's cost over the direct estimate (the value f(theta), the host round trips, the tensors)")


def minimizer(args: argparse.Namespace) -> None:
    us = 1e6
    print()
    print(f"A minimize run on f(x) = sum(floor(x)^2), median of {4 * args.repeats}, alternating; microseconds per run")
    header = f"{'n':>5} | {'maxfev':>6} | {'plateau_free.minimize':>21} | {'scipy.optimize.minimize':>23} | {'+ scipy':>8}"
    print(header)
    print("-" * len(header))

    def f(x: np.ndarray) -> float:
        return float(np.sum(np.floor(x) ** 2))

    for dim, budget in [(2, 200), (10, 1000)]:
        x0 = np.full(dim, 2.5)
        runs = {
            "ours": lambda: plateau_free.minimize(f, x0, budget=budget),
            "scipy": lambda: scipy.optimize.minimize(
                f, x0, method=plateau_free.scipy.method, options={"maxfev": budget}
            ),
        }
        # The two alternate, so that a change in the machine's load touches both alike; the
        # median, as a single run is short enough for one slow time slice to double it.
        times: dict[str, list[float]] = {name: [] for name in runs}
        for _ in range(4 * args.repeats):
            for name, run in runs.items():
                start = time.perf_counter()
                run()
                times[name].append(time.perf_counter() - start)
        ours, theirs = (float(np.median(times[name])) for name in ("ours", "scipy"))
        print(f"{dim:>5} | {budget:>6} | {ours * us:>21.0f} | {theirs * us:>23.0f} | {(theirs - ours) * us:>8.0f}")
    print("+ scipy: scipy.optimize.minimize's own checks and the OptimizeResult it returns")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="best of this many timings")
    parser.add_argument("--calls", type=int, default=200, help="calls per timing")
    args = parser.parse_args()
    gradients(args)
    minimizer(args)


if __name__ == "__main__":
    main()
