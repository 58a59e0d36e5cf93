"""Stronger peers for ``docs/results/compare.md``: pycma's BIPOP-CMA-ES and nevergrad's NGOpt.

    scripts/compare-peers                  # the page's command: runs this, then the page

By hand (what ``scripts/compare-peers`` does)::

    cargo run --release --example compare -- --export target/compare-peers/instances.txt
    target/venv-peers/bin/python -m studies peers \\
        --instances target/compare-peers/instances.txt --out target/compare-peers/peers.csv

The instances (function, dimension, seed: the shift, the rotation and the start point) are
those of ``examples/compare``, exported by it; the functions are the same definitions as
``examples/compare/functions.rs``, written again in numpy below. Before any run every
instance's values at six points are compared with the values Rust wrote beside them, and the
harness stops if one differs by more than 1e-9 relative.

The rows are appended to ``--out`` as the runs end, in order of dimension, and a run already
there is not run again.

Every method gets what ``minimize`` gets: the start point ``x0``, a budget of ``factor * n``
evaluations (only the first ``budget`` count), and the target 1e-8 as a reason to stop. The
rows have the columns of ``compare.csv``.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import sys
import time
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import NDArray

TARGETS = [10.0**k for k in range(2, -9, -1)]
GROUPS = {
    "sphere": "smooth",
    "ellipsoid": "ill-conditioned",
    "rosenbrock": "ill-conditioned",
    "rastrigin": "multimodal",
    "step-ellipsoid": "plateau",
    "sum-of-floors": "plateau",
}
METHODS = ("bipop-cma", "ngopt")
Vector = NDArray[np.float64]


@dataclass
class Instance:
    """One problem of the grid, as ``compare --export`` wrote it."""

    kind: str
    n: int
    seed: int
    shift: Vector
    rotation: Vector  # n x n
    x0: Vector
    checks: list[tuple[Vector, float]]

    def value(self, x: Vector) -> float:
        """``f(x) - f(x*)``, as ``Problem::eval`` in ``examples/compare/functions.rs``."""
        n = self.n
        ramp = np.arange(n) / (n - 1) if n > 1 else np.zeros(n)
        d = x - self.shift
        if self.kind == "sphere":
            return float(d @ d)
        z = self.rotation @ d
        if self.kind == "ellipsoid":
            return float(np.sum(10.0 ** (6.0 * ramp) * z * z))
        if self.kind == "rosenbrock":
            z = max(math.sqrt(n), 8.0) / 8.0 * z + 1.0
            return float(np.sum(100.0 * (z[:-1] ** 2 - z[1:]) ** 2 + (z[:-1] - 1.0) ** 2))
        if self.kind == "rastrigin":
            return float(10.0 * (n - np.sum(np.cos(2.0 * math.pi * z))) + z @ z)
        if self.kind == "step-ellipsoid":
            z = z * 10.0 ** (0.5 * ramp)
            r = np.where(np.abs(z) > 0.5, np.floor(0.5 + z), np.floor(0.5 + 10.0 * z) / 10.0)
            return float(0.1 * max(abs(z[0]) / 1e4, float(np.sum(10.0 ** (2.0 * ramp) * r * r))))
        if self.kind == "sum-of-floors":
            return float(np.sum(np.floor(np.abs(z))))
        raise ValueError(f"unknown function {self.kind!r}")


def read_instances(path: str) -> list[Instance]:
    """The instances of ``compare --export``: a header line, the shift, the rotation, the
    start, then six lines of a check point and its value."""
    lines = open(path, encoding="utf-8").read().splitlines()
    out, i = [], 0
    while i < len(lines):
        kind, n_text, seed_text = lines[i].split()
        n = int(n_text)

        def floats(line: str) -> Vector:
            return np.array([float(v) for v in line.split()], dtype=np.float64)

        shift, rotation, x0 = (floats(lines[i + k]) for k in (1, 2, 3))
        checks = []
        for line in lines[i + 4 : i + 10]:
            v = floats(line)
            checks.append((v[:-1], float(v[-1])))
        if shift.size != n or rotation.size != n * n or x0.size != n:
            raise ValueError(f"{path}: instance {kind} n={n} seed={seed_text} is malformed")
        out.append(Instance(kind, n, int(seed_text), shift, rotation.reshape(n, n), x0, checks))
        i += 10
    return out


def check(instance: Instance) -> None:
    """Stops if a value here differs from Rust's by more than 1e-9 relative (1e-12 absolute)."""
    for x, expected in instance.checks:
        got = instance.value(x)
        if not abs(got - expected) <= 1e-9 * abs(expected) + 1e-12:
            raise SystemExit(
                f"{instance.kind} n={instance.n} seed={instance.seed}: numpy gives {got!r}, "
                f"Rust {expected!r}: the definitions differ"
            )


class BudgetSpent(Exception):
    """Raised by the recorder at the evaluation after the budget, to leave the optimiser."""


class Recorder:
    """Counts evaluations and the first evaluation at which each target is reached, as the
    ``Recorder`` of ``examples/compare/main.rs``."""

    def __init__(self, instance: Instance, budget: int) -> None:
        self.instance, self.budget = instance, budget
        self.evals, self.best = 0, math.inf
        self.hits: list[int | None] = [None] * len(TARGETS)

    def __call__(self, x: Vector) -> float:
        if self.evals >= self.budget or self.best <= TARGETS[-1]:
            raise BudgetSpent
        v = self.instance.value(np.asarray(x, dtype=np.float64))
        self.evals += 1
        if v < self.best:
            self.best = v
            for k, t in enumerate(TARGETS):
                if self.hits[k] is None and v <= t:
                    self.hits[k] = self.evals
        return v


def run_bipop(rec: Recorder, seed: int) -> None:
    """pycma's ``fmin2`` with BIPOP restarts (``restarts=9, bipop=True``), step size 2 as the
    ``cmaes`` rows; the first run starts at x0, each restart at a uniform point of [-4, 4]^n."""
    import cma

    inst = rec.instance
    rng = np.random.default_rng(seed)
    starts = [0]

    def x0() -> Vector:
        starts[0] += 1
        return inst.x0.copy() if starts[0] == 1 else rng.uniform(-4.0, 4.0, inst.n)

    options = {
        "seed": seed + 1,  # pycma takes 0 as "from the clock"
        "maxfevals": rec.budget,
        "ftarget": TARGETS[-1],
        "verbose": -9,
        "verb_log": 0,
        "verb_disp": 0,
    }
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            cma.fmin2(rec, x0, 2.0, options, restarts=9, bipop=True)
        except BudgetSpent:
            pass


def run_ngopt(rec: Recorder, seed: int) -> None:
    """nevergrad's NGOpt on an unbounded array starting at x0, its defaults otherwise."""
    import nevergrad as ng

    param = ng.p.Array(init=rec.instance.x0.copy())
    param.random_state = np.random.RandomState(seed)
    opt = ng.optimizers.NGOpt(parametrization=param, budget=rec.budget, num_workers=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            for _ in range(rec.budget):
                candidate = opt.ask()
                opt.tell(candidate, rec(candidate.value))
        except BudgetSpent:
            pass


RUNNERS: dict[str, Callable[[Recorder, int], None]] = {"bipop-cma": run_bipop, "ngopt": run_ngopt}


def one(job: tuple[Instance, str, int]) -> str:
    """One run as a row of ``compare.csv``."""
    inst, method, factor = job
    rec = Recorder(inst, factor * inst.n)
    start = time.perf_counter()
    RUNNERS[method](rec, inst.seed)
    seconds = time.perf_counter() - start
    reached = sum(h is not None for h in rec.hits)
    hits = ",".join("" if h is None else str(h) for h in rec.hits)
    row = (
        f"{method},{inst.kind},{GROUPS[inst.kind]},{inst.n},{inst.seed},{rec.evals},"
        f"{rec.best:e},{reached},{seconds:.3f},{hits}"
    )
    print(f"{method:<10} {inst.kind:<15} n={inst.n:<3} seed={inst.seed} best {rec.best:10.3e} "
          f"targets {reached:2}/11  {seconds:.2f}s", file=sys.stderr, flush=True)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--instances", required=True, help="the file of compare --export")
    parser.add_argument("--out", required=True, help="the CSV to write")
    parser.add_argument("--factor", type=int, default=1000, help="budget = factor * n")
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--jobs", type=int, default=1, help="runs at once (processes)")
    args = parser.parse_args()
    methods = args.methods.split(",")
    for m in methods:
        if m not in RUNNERS:
            parser.error(f"--methods: unknown method {m!r} (known: {', '.join(METHODS)})")
    if args.factor < 1 or args.jobs < 1:
        parser.error("--factor and --jobs must be at least 1")
    instances = read_instances(args.instances)
    for inst in instances:
        check(inst)
    print(f"{len(instances)} instances, values agree with Rust's", file=sys.stderr)
    header = "method,function,group,n,seed,evaluations,best,targets_reached,seconds"
    header += "".join(f",evals_to_{t:.0e}".replace("e+0", "e").replace("e-0", "e-") for t in TARGETS)
    # Rows are appended as runs end, and the runs already in --out are not run again: a run
    # stopped (by the machine's time) goes on where it was.
    done: set[tuple[str, str, int, int]] = set()
    try:
        with open(args.out, encoding="utf-8") as f:
            lines = f.read().splitlines()
        if lines[:1] != [header]:
            raise SystemExit(f"{args.out} is not a CSV of this harness; move it away")
        for line in lines[1:]:
            m, kind, _group, n, seed = line.split(",")[:5]
            done.add((m, kind, int(n), int(seed)))
    except FileNotFoundError:
        with open(args.out, "w", encoding="utf-8") as f:
            f.write(header + "\n")
    jobs = [
        (inst, m, args.factor)
        for inst in instances
        for m in methods
        if (m, inst.kind, inst.n, inst.seed) not in done
    ]
    # The small dimensions first: each finished row counts even if the large ones cannot be
    # afforded.
    jobs.sort(key=lambda job: job[0].n)
    print(f"{len(done)} runs already in {args.out}, {len(jobs)} to run", file=sys.stderr)
    with multiprocessing.Pool(args.jobs) as pool:
        for row in pool.imap(one, jobs, chunksize=1):
            with open(args.out, "a", encoding="utf-8") as f:
                f.write(row + "\n")

if __name__ == "__main__":
    main()
