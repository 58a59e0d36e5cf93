"""MPI's speed-up and overhead: runs ``mpi/examples/scaling`` and writes its tables as a page.

    cargo build --release -p plateau-free-mpi --example scaling   # needs Open MPI: scripts/install-mpi
    python -m studies mpi-scaling [--max-ranks 4] [--reps 7] [--page docs/results/mpi-scaling.md]

The example launches ``mpirun -n R --oversubscribe`` of itself for R = 2 to ``--max-ranks``
ranks (R - 1 workers) and the sequential baselines as plain processes, every process on one
thread, and prints two markdown tables: the time of an estimate of 12 points (an objective that
sleeps, then a SHADOW render) with its speed-up and efficiency, and the overhead of an estimate
of a zero-cost objective against the size of its points, under both ways of waiting. This
study runs it and writes what it prints as a results page (``studies/_page.py``).
"""

from __future__ import annotations

import argparse
import subprocess
import sys

from studies import _page

BINARY = _page.REPO / "target" / "release" / "examples" / "scaling"

PAGE = """# MPI: speed-up and overhead of `plateau-free-mpi`

Made by `{command}` (after `cargo build --release -p plateau-free-mpi --example scaling`),
which runs `target/release/examples/scaling`, on a machine shared with other jobs: ranks beyond
its cores oversubscribe it, and the CPU-bound rows vary from run to run; the sleeping
objective uses no CPU, so its rows measure the distribution alone. What the tables measure and
what follows from them: [`docs/scale-out.md`](../scale-out.md#measured-here).

{output}"""


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--max-ranks", type=int, default=4, help="the most ranks, workers + 1 (default 4)")
    p.add_argument("--reps", type=int, default=7, help="estimates per measurement (default 7)")
    p.add_argument("--page", default="docs/results/mpi-scaling.md", help="the page to write")
    args = p.parse_args()
    if not BINARY.is_file():
        sys.exit(f"{BINARY} is missing: cargo build --release -p plateau-free-mpi --example scaling")
    run = subprocess.run([str(BINARY), "--max-ranks", str(args.max_ranks), "--reps", str(args.reps)],
                         capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"{BINARY.name} failed (exit {run.returncode}):\n{run.stderr}")
    print(run.stdout, end="")
    command = " ".join(["python -m studies mpi-scaling", *sys.argv[1:]])
    _page.write(args.page, PAGE.format(command=command, output=run.stdout.strip()))


if __name__ == "__main__":
    main()
