"""``python -m studies coco``: COCO's ``bbob`` and ``bbob-mixint`` suites (the
coco-experiment package, ``cocoex``) for ``plateau_free.minimize`` and its peers, and the page
``docs/results/coco.md``.

- ``run``: every (suite, function, dimension, instance, solver) of the grid asked for, with a
  budget of ``1000 n`` evaluations, one fixed seed per instance, the run ended at
  ``f_opt + 1e-8``; one JSON line per run in ``RUNS/runs.jsonl`` (a run already there is not
  made again, so an interrupted grid goes on). ``f_opt`` is the one COCO's own logger states
  in its data files (for bbob-mixint it differs from bbob's on some functions: f15
  instance 1 is 100, not 1000), read once per problem from a logger run in a temporary
  folder.
- ``page``: ``docs/results/coco.md`` from the runs (``page.py``).

The peers (``solvers.py``) come from ``studies/coco/requirements.txt``:
``scripts/venv target/venv-coco studies/coco/requirements.txt``, then the plateau_free wheel
(``scripts/build-python target/wheels``) installed beside.
"""

from __future__ import annotations

import argparse
import glob
import json
import multiprocessing
import os
import re
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from studies.coco.solvers import DECLARES_INTEGERS, SOLVERS, SUBSET_SOLVERS, Box, Done

DEFAULT_RUNS = "docs/results/coco"
_SUITES: dict[str, Any] = {}
_FOPT: dict[tuple[str, int, int, int], float] = {}


def suite(name: str) -> Any:
    import cocoex

    if name not in _SUITES:
        _SUITES[name] = cocoex.Suite(name, "", "")
    return _SUITES[name]


def fopt(name: str, fid: int, n: int, inst: int) -> float:
    """``f_opt`` as COCO's logger writes it (``Fopt (...)`` in its data files' header)."""
    import cocoex

    key = (name, fid, n, inst)
    if key not in _FOPT:
        here = os.getcwd()
        with tempfile.TemporaryDirectory() as tmp:
            os.chdir(tmp)
            try:
                cocoex.log_level("warning")
                problem = suite(name).get_problem_by_function_dimension_instance(fid, n, inst)
                observer = cocoex.Observer("bbob", "result_folder: fopt")
                problem.observe_with(observer)
                problem(problem.initial_solution)
                problem.free()
                del observer
                header = open(glob.glob("exdata/**/*.dat", recursive=True)[0]).readline()
            finally:
                os.chdir(here)
        _FOPT[key] = float(re.search(r"Fopt \(([^)]+)\)", header).group(1))
    return _FOPT[key]


class Counted:
    """The problem behind a counter: the best value and the evaluations. ``strict`` (the
    peers): a call after the budget or the final target raises ``Done``; otherwise (the
    library, which is given the budget and the target itself) every call is answered."""

    def __init__(self, problem: Any, budget: int, target: float, strict: bool) -> None:
        self.problem, self.budget, self.target, self.strict = problem, budget, target, strict
        self.evaluations = 0
        self.best = float("inf")

    def __call__(self, x: Any) -> float:
        if self.strict and (self.evaluations >= self.budget or self.best <= self.target):
            raise Done
        if self.evaluations >= self.budget:
            raise RuntimeError(f"the solver asked for more than its budget of {self.budget}")
        value = float(self.problem(np.asarray(x, dtype=float)))
        self.evaluations += 1
        self.best = min(self.best, value)
        return value


def one(task: tuple[str, int, int, int, str, int]) -> dict[str, Any]:
    """One run: the problem, its f_opt, the solver; the best precision reached."""
    name, fid, n, inst, solver, factor = task
    problem = suite(name).get_problem_by_function_dimension_instance(fid, n, inst)
    optimum = fopt(name, fid, n, inst)
    budget = factor * n
    box = Box(x0=np.array(problem.initial_solution, dtype=float),
              lower=np.array(problem.lower_bounds, dtype=float),
              upper=np.array(problem.upper_bounds, dtype=float),
              integers=int(problem.number_of_integer_variables), budget=budget, seed=inst,
              target=optimum + 1e-8)
    counted = Counted(problem, budget, box.target, strict=not solver.startswith("minimize"))
    start = time.perf_counter()
    try:
        SOLVERS[solver][0](counted, box)
    except Done:
        pass
    seconds = time.perf_counter() - start
    problem.free()
    return {"suite": name, "f": fid, "n": n, "instance": inst, "solver": solver,
            "budget": budget, "seed": inst, "fopt": optimum, "best": counted.best,
            "precision": max(counted.best - optimum, 0.0), "evaluations": counted.evaluations,
            "seconds": round(seconds, 3)}


def ranges(text: str) -> list[int]:
    """``1-5,7`` as ``[1, 2, 3, 4, 5, 7]`` (positive integers; argparse's type)."""
    out: list[int] = []
    try:
        for part in text.split(","):
            lo, _, hi = part.partition("-")
            out += list(range(int(lo), int(hi or lo) + 1))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a list of numbers and ranges like 1-5,7")
    if not out or min(out) < 1:
        raise argparse.ArgumentTypeError(f"{text!r} names no positive number")
    return out


def positive(text: str) -> int:
    """A positive integer (argparse's type)."""
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive integer")
    return int(text)


def solver_list(text: str) -> list[str]:
    """Solver names, comma-separated (argparse's type)."""
    names = text.split(",")
    unknown = [s for s in names if s not in SOLVERS]
    if unknown:
        raise argparse.ArgumentTypeError(f"unknown solvers {unknown}: choose from {list(SOLVERS)}")
    return names


def suite_list(text: str) -> list[str]:
    names = text.split(",")
    if any(s not in ("bbob", "bbob-mixint") for s in names):
        raise argparse.ArgumentTypeError(f"{text!r}: the suites are bbob and bbob-mixint")
    return names


def tasks(a: argparse.Namespace, done: set[tuple]) -> Iterator[tuple]:
    for name in a.suites:
        solvers = a.solvers
        if name == "bbob":  # nothing to declare: the declared run and CMAwM are the box's
            solvers = [s for s in solvers if s not in DECLARES_INTEGERS]
        # The largest dimensions first, so that the slowest runs are not left for the end.
        for n in sorted(a.dims, reverse=True):
            for fid in a.functions:
                for inst in a.instances:
                    for solver in solvers:
                        key = (name, fid, n, inst, solver, a.budget * n)
                        if key not in done:
                            yield (name, fid, n, inst, solver, a.budget)


def run_main(a: argparse.Namespace) -> None:
    out = Path(a.runs) / "runs.jsonl"
    out.parent.mkdir(parents=True, exist_ok=True)
    done = set()
    if out.exists():
        for line in out.read_text().splitlines():
            r = json.loads(line)
            done.add((r["suite"], r["f"], r["n"], r["instance"], r["solver"], r["budget"]))
    todo = list(tasks(a, done))
    print(f"{len(todo)} runs to make ({len(done)} already in {out})", file=sys.stderr)
    with out.open("a") as sink, multiprocessing.Pool(a.jobs) as pool:
        for k, r in enumerate(pool.imap_unordered(one, todo), 1):
            sink.write(json.dumps(r) + "\n")
            sink.flush()
            if k % 20 == 0 or k == len(todo):
                print(f"{k}/{len(todo)}: {r['suite']} f{r['f']} n={r['n']} {r['solver']} "
                      f"{r['precision']:.2e} ({r['seconds']} s)", file=sys.stderr)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="make the runs of a grid (resumes)")
    r.add_argument("--suites", type=suite_list, default="bbob-mixint,bbob")
    r.add_argument("--dims", type=ranges, default="5,10,20", help="e.g. 5,10,20,40")
    r.add_argument("--functions", type=ranges, default="1-24")
    r.add_argument("--instances", type=ranges, default="1-5")
    r.add_argument("--solvers", type=solver_list,
                   default=",".join(s for s in SOLVERS if s not in SUBSET_SOLVERS),
                   help=f"default: all but {', '.join(SUBSET_SOLVERS)} (run on a subset)")
    r.add_argument("--budget", type=positive, default=1000,
                   help="evaluations per dimension (default 1000)")
    r.add_argument("--jobs", type=positive, default=2, help="processes (default 2)")
    r.add_argument("--runs", default=DEFAULT_RUNS, help="folder of runs.jsonl")
    p = sub.add_parser("page", help="write the page from the runs")
    p.add_argument("--runs", default=DEFAULT_RUNS)
    p.add_argument("--page", default="docs/results/coco.md")
    p.add_argument("--made-by", help="the commands of a page of a part of the grid, stated on it")
    a = parser.parse_args()
    if a.command == "run":
        run_main(a)
    else:
        from studies.coco.page import write_page

        write_page(Path(a.runs), Path(a.page), a.made_by)


if __name__ == "__main__":
    main()
