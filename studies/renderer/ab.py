"""Compares two builds of the path tracer: CPU seconds per render, task by task.

Usage: python -m studies render-ab BEFORE AFTER [--rounds R] [--repeat K] [--threads T] [TASK ...]

BEFORE and AFTER are `pathtracer` binaries. Each round runs, for every task, both binaries'
`pathtracer render TASK --target --repeat K --threads T` (the order of the two turning every
round, so that a drift in the machine's load falls on both) and reads `render_cpu_seconds`:
the render alone, scene set-up excluded, the time its threads spent on a core (time the cores
gave to other jobs is left out). Prints a Markdown table of the medians over the rounds and
their ratio. Defaults: 5 rounds, K = 5, one thread, all seven tasks. Run it under `nice` on a
shared machine; the outputs go to a temporary folder.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile

from studies.renderer.binary import TASKS, render_report


def cpu_seconds(binary: str, task: str, repeat: int, threads: int, out: str) -> float:
    """`render_cpu_seconds` of one `pathtracer render` run (the mean of its `repeat`)."""
    report = render_report(binary, task, repeat, threads, out)
    if "render_cpu_seconds" not in report:
        sys.exit(f"render-ab: {binary} printed no render_cpu_seconds for {task}")
    return float(report["render_cpu_seconds"])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("tasks", nargs="*", default=list(TASKS))
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args(argv)
    for name in ("rounds", "repeat", "threads"):
        if getattr(a, name) < 1:
            ap.error(f"--{name} must be at least 1")
    bad = [t for t in a.tasks if t not in TASKS]
    if bad:
        ap.error(f"unknown task {bad[0]!r} (one of {', '.join(TASKS)})")
    times = {t: ([], []) for t in a.tasks}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(a.rounds):
            for t in a.tasks:
                order = [0, 1] if r % 2 == 0 else [1, 0]
                for k in order:
                    binary = (a.before, a.after)[k]
                    s = cpu_seconds(binary, t, a.repeat, a.threads, f"{tmp}/{t}.exr")
                    times[t][k].append(s)
    print(f"CPU seconds per render, median of {a.rounds} interleaved rounds, "
          f"each the median of {a.repeat} renders, {a.threads} thread(s)\n")
    print("| task | before (s) | after (s) | after / before |")
    print("|---|---|---|---|")
    for t in a.tasks:
        b, f = (statistics.median(x) for x in times[t])
        print(f"| {t} | {b:.4f} | {f:.4f} | {f / b:.3f} |")


if __name__ == "__main__":
    main()
