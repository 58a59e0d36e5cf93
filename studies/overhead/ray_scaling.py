"""Speed-up of plateau_free.ray.RayEvaluator against the number of workers, and its overhead.

    python -m studies ray-scaling            # after pip install "./python[ray]"
    python -m studies ray-scaling --cost 0.1 --samples 32 --workers 1 2 4 8
    python -m studies ray-scaling --page docs/results/ray-scaling.md

Starts a local Ray instance (``--address`` joins a running cluster instead) and prints:

1. Scaling: the wall time of one gradient estimate of N points (``PlateauFreeGradient(...,
   batched=True, seeded=True)`` with a RayEvaluator of K workers) against K, beside the
   sequential estimate (the same objective called in this process) and the ideal
   ``cost * ceil(N / K)``. The objective sleeps ``--cost`` seconds (a stand-in for a renderer
   or simulator that waits on its own device); ``--busy`` spins the CPU instead, which on this
   machine cannot scale past its cores. Every parallel estimate is checked bit for bit
   against the sequential one.
2. Overhead: a zero-cost objective, one task per point and the default chunking, so the time
   per point is Ray's scheduling and the evaluator's bookkeeping; then points of ``--big``
   float64 values each (transfer through the object store); then the start-up of Ray and of
   the actors.
3. The cost model ``T_par(N, K) = max(ceil(N/K) T_eval, tasks * o) + N b / B + L`` with the
   per-task overhead o (the zero-cost run with K = 2), the latency L (the scaling run's wall time
   beyond the ideal, median over K) and B measured here, extrapolated to ``--machines`` machines
   with ``--network-mbps`` between them (assumed: it cannot be measured on one machine).

With ``--page PATH`` the same output is also written as a results page (``studies/_page.py``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import os
import sys
import time

import numpy as np

os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")

import ray  # noqa: E402

import plateau_free  # noqa: E402
from plateau_free.ray import RayEvaluator  # noqa: E402

from studies import _page  # noqa: E402


def make_objective(cost: float, busy: bool):
    """make_fun: an objective of ``cost`` seconds, a deterministic function of (x, seed)."""

    def make():
        def fun(x, seed=0):
            if cost > 0:
                if busy:
                    end = time.perf_counter() + cost
                    while time.perf_counter() < end:
                        pass
                else:
                    time.sleep(cost)
            return float(np.sum((x[:8] - 0.25) ** 2)) + (seed % 1000) * 1e-6

        return fun

    return make


def timed(run) -> float:
    start = time.perf_counter()
    run()
    return time.perf_counter() - start


def best_of(repeats: int, run) -> float:
    return min(timed(run) for _ in range(repeats))


def scaling(args, options) -> float:
    make = make_objective(args.cost, args.busy)
    x0 = np.linspace(-1.0, 1.0, args.dim)
    sequential_grad = plateau_free.PlateauFreeGradient(make(), samples=args.samples, seeded=True, seed=5)
    start = time.perf_counter()
    expected = sequential_grad.estimate(x0, 0.3)
    sequential = time.perf_counter() - start

    kind = "busy-wait" if args.busy else "sleep"
    print(f"Scaling: one estimate of N = {args.samples} points, n = {args.dim}, objective {kind} {args.cost} s per call")
    print(f"sequential (in this process): {sequential:.3f} s")
    latencies = []
    header = f"{'K':>3} | {'wall s':>7} | {'ideal s':>7} | {'speed-up':>8} | {'efficiency':>10} | {'start s':>7} | bit-equal"
    print(header)
    print("-" * len(header))
    for k in args.workers:
        start = time.perf_counter()
        with RayEvaluator(make, num_workers=k, **options) as evaluator:
            started = time.perf_counter() - start
            grad = plateau_free.PlateauFreeGradient(evaluator, samples=args.samples, batched=True, seeded=True, seed=5)
            grad.estimate(x0, 0.3)  # warm: the actors' first call
            walls = []
            same = True
            for _ in range(args.repeats):
                grad.reset()
                start = time.perf_counter()
                g = grad.estimate(x0, 0.3)
                walls.append(time.perf_counter() - start)
                same = same and bool(np.array_equal(g, expected))
        wall = min(walls)
        ideal = args.cost * math.ceil(args.samples / k)
        speedup = sequential / wall
        print(f"{k:>3} | {wall:7.3f} | {ideal:7.3f} | {speedup:8.2f} | {speedup / k:10.2f} | {started:7.2f} | {same}")
        latencies.append(wall - ideal)
    print()
    return float(np.median(latencies))


def overhead(args, options) -> tuple:
    make = make_objective(0.0, False)
    rng = np.random.default_rng(1)
    n_points = args.overhead_points
    small = rng.normal(size=(n_points, 4))
    seeds = np.arange(n_points, dtype=np.uint64)
    fun = make()
    local = best_of(3, lambda: [fun(x, int(s)) for x, s in zip(small, seeds)])
    print(f"Overhead: zero-cost objective, N = {n_points} points of n = 4 (best of 3)")
    print(f"in this process, a Python loop: {1e6 * local / n_points:8.1f} us per point")
    print(f"{'K':>3} | {'chunking':>22} | {'tasks':>5} | {'wall s':>7} | {'us per point':>12} | {'us per task':>11}")
    print("-" * 75)
    figures = {}
    for k in [1, 2]:
        with RayEvaluator(make, num_workers=k, **options) as evaluator:
            evaluator(small[:8], seeds[:8])  # warm
            for label, size in [("one point per task", 1), ("default ceil(N/(4K))", None)]:
                evaluator.chunk_size = size
                chunk = size or math.ceil(n_points / (4 * k))
                tasks = math.ceil(n_points / chunk)
                wall = best_of(3, lambda: evaluator(small, seeds))
                figures[(k, label)] = wall
                print(f"{k:>3} | {label:>22} | {tasks:>5} | {wall:7.3f} | {1e6 * wall / n_points:12.1f} | {1e6 * wall / tasks:11.1f}")
    print()

    big = rng.normal(size=(args.big_points, args.big))
    big_seeds = np.arange(args.big_points, dtype=np.uint64)
    megabytes = big.nbytes / 1e6
    print(f"Transfer: N = {args.big_points} points of n = {args.big} float64 ({big.itemsize * args.big / 1e6:.2f} MB each, {megabytes:.1f} MB in all), zero-cost objective, one point per task")
    with RayEvaluator(make, num_workers=2, chunk_size=1, **options) as evaluator:
        evaluator(big[:2], big_seeds[:2])  # warm
        wall = best_of(3, lambda: evaluator(big, big_seeds))
        small_wall = best_of(3, lambda: evaluator(small[: args.big_points], seeds[: args.big_points]))
    per_point = (wall - small_wall) / args.big_points
    print(f"K = 2: {wall:.3f} s ({1e3 * wall / args.big_points:.2f} ms per point; the same count of n = 4 points: {small_wall:.3f} s)")
    bandwidth = megabytes / max(wall - small_wall, 1e-9)
    print(f"transfer: {1e3 * per_point:.2f} ms per point beyond a small one, {bandwidth:.0f} MB/s")
    print()
    per_task = figures[(2, "one point per task")] / n_points
    return per_task, bandwidth


def model(args, per_task: float, latency: float, bandwidth: float) -> None:
    """T_par(N, K) = max(ceil(N/K) T_eval, tasks o) + N b / B + L, extrapolated to K machines."""
    k = args.machines
    n_points = args.model_points
    network = args.network_mbps
    print(
        f"Cost model: T_par = max(ceil(N/K) T_eval, tasks * o) + N b / B + L with o = {1e3 * per_task:.2f} ms per task "
        f"and L = {1e3 * latency:.0f} ms (measured above), B = {bandwidth:.0f} MB/s here, {network:.0f} MB/s assumed between machines"
    )
    print(f"Extrapolated: K = {k} machines, N = {n_points} points per estimate, one point per task")
    print(f"{'T_eval':>8} | {'n':>7} | {'T_seq s':>9} | {'T_par s':>8} | {'speed-up':>8} | {'efficiency':>10}")
    print("-" * 66)
    for t_eval in [0.001, 0.01, 0.1, 1.0, 10.0]:
        for dim in [16, 100_000]:
            sequential = n_points * t_eval
            parallel = max(math.ceil(n_points / k) * t_eval, n_points * per_task) + n_points * dim * 8 / (network * 1e6) + latency
            speedup = sequential / parallel
            print(f"{t_eval:8.3f} | {dim:>7} | {sequential:9.2f} | {parallel:8.3f} | {speedup:8.1f} | {speedup / k:10.2f}")
    print()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cost", type=float, default=0.1, help="seconds per call of the objective (default 0.1)")
    parser.add_argument("--busy", action="store_true", help="spin the CPU instead of sleeping")
    parser.add_argument("--samples", type=int, default=32, help="N, points per estimate (default 32)")
    parser.add_argument("--dim", type=int, default=16, help="n of the scaling run (default 16)")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2, 4, 8], help="values of K (default 1 2 4 8)")
    parser.add_argument("--repeats", type=int, default=2, help="estimates per K, best taken (default 2)")
    parser.add_argument("--overhead-points", type=int, default=2000, help="N of the zero-cost run (default 2000)")
    parser.add_argument("--big", type=int, default=100_000, help="n of the transfer run (default 1e5)")
    parser.add_argument("--big-points", type=int, default=32, help="N of the transfer run (default 32)")
    parser.add_argument("--machines", type=int, default=100, help="K of the extrapolation (default 100)")
    parser.add_argument("--model-points", type=int, default=200, help="N of the extrapolation (default 200)")
    parser.add_argument("--network-mbps", type=float, default=1250.0, help="MB/s between machines assumed (default 1250: 10 GbE)")
    parser.add_argument("--address", default=None, help="a running Ray cluster's address (default: a local instance)")
    parser.add_argument("--skip-scaling", action="store_true")
    parser.add_argument("--skip-overhead", action="store_true")
    parser.add_argument("--page", default=None, help="also write the output as this results page")
    args = parser.parse_args()
    if args.page is None:
        measure(args)
        return
    printed = io.StringIO()
    with contextlib.redirect_stdout(_Tee(sys.stdout, printed)):
        measure(args)
    command = " ".join(["python -m studies ray-scaling", *sys.argv[1:]])
    _page.write(args.page, PAGE.format(command=command, output=printed.getvalue().rstrip()))


PAGE = """# Ray: speed-up and overhead of `RayEvaluator`

Made by `{command}` (after `pip install "./python[ray]"`), on a machine shared with other
jobs: compare within a table. What each part measures, and the cost model fitted to it:
[`docs/scale-out.md`](../scale-out.md#measured-speed-up-and-overhead).

```text
{output}
```"""


class _Tee(io.TextIOBase):
    """Writes to every stream it holds: the terminal and the page's copy."""

    def __init__(self, *streams: io.TextIOBase) -> None:
        self.streams = streams

    def write(self, text: str) -> int:
        for stream in self.streams:
            stream.write(text)
        return len(text)


def measure(args: argparse.Namespace) -> None:
    """Starts Ray, prints the scaling, the overhead and the cost model, stops Ray."""
    start = time.perf_counter()
    if args.address is None:
        # Logical CPUs: as many as the largest K, so that every actor gets one. A sleeping
        # objective needs no core; a busy one shares the machine's.
        ray.init(address="local", num_cpus=max(args.workers), include_dashboard=False, log_to_driver=False, configure_logging=False)
    else:
        ray.init(address=args.address, log_to_driver=False)
    print(f"ray.init: {time.perf_counter() - start:.2f} s (Ray {ray.__version__}, {os.cpu_count()} cores here)")
    print()
    options = {"num_cpus_per_worker": 1}
    try:
        latency = scaling(args, options) if not args.skip_scaling else None
        if not args.skip_overhead:
            per_task, bandwidth = overhead(args, options)
            if latency is not None:
                model(args, per_task, latency, bandwidth)
    finally:
        ray.shutdown()


if __name__ == "__main__":
    main()
