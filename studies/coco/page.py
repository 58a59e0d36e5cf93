"""``docs/results/coco.md`` from the runs of ``python -m studies coco run`` (``runs.jsonl``):
the mean fraction of the 11 targets ``f_opt + 10^k``, ``k = 2, 1, ..., -8``, that each
solver's best value reached within its budget, per dimension and per function group."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable, Iterable

from studies import _page
from studies.coco.solvers import SOLVERS, SUBSET_SOLVERS

GROUPS = {"f1-14": range(1, 15), "f15-24": range(15, 25)}
DEVELOPMENT = range(1, 6)
"""The instances looked at while the library was changed; the others are a second sample."""


def reached(precision: float) -> float:
    """The fraction of the 11 targets ``10^2, ..., 10^-8`` that ``best - f_opt`` reached."""
    return sum(precision <= 10.0**k for k in range(2, -9, -1)) / 11


def mean(xs: Iterable[float]) -> str:
    xs = list(xs)
    return f"{sum(xs) / len(xs):.3f}" if xs else "-"


def table(runs: list[dict[str, Any]], columns: list[tuple[str, Callable[[dict], bool]]]) -> list[str]:
    """Solvers as rows (the harness's order), one column per filter, the mean score of the
    runs it keeps; the best of each column in bold."""
    solvers = [s for s in SOLVERS if any(r["solver"] == s for r in runs)]
    cells = {s: [mean(reached(r["precision"]) for r in runs if r["solver"] == s and keep(r))
                 for _, keep in columns] for s in solvers}
    for j in range(len(columns)):
        scores = [cells[s][j] for s in solvers if cells[s][j] != "-"]
        top = max(scores, default=None)
        for s in solvers:
            if cells[s][j] == top:
                cells[s][j] = f"**{top}**"
    rows = [[SOLVERS[s][1], *cells[s]] for s in solvers]
    return _page.table(["", *[name for name, _ in columns]], rows)


def spans(xs: list[int]) -> str:
    """``[1, 2, 3, 5]`` as ``1-3, 5``."""
    out, start = [], None
    for i, x in enumerate(xs):
        start = x if start is None else start
        if i + 1 == len(xs) or xs[i + 1] != x + 1:
            out.append(f"{start}-{x}" if x > start else f"{x}")
            start = None
    return ", ".join(out)


def suite_section(name: str, runs: list[dict[str, Any]], note: str = "") -> list[str]:
    dims = sorted({r["n"] for r in runs})
    grid = "; ".join(
        f"n = {n}: functions {spans(sorted({r['f'] for r in runs if r['n'] == n}))}, instances "
        f"{spans(sorted({r['instance'] for r in runs if r['n'] == n}))}" for n in dims)
    lines = [f"## {name}", "", f"{len(runs)} runs, budget 1000 n ({grid}).{note}", ""]
    by_n = [(f"n = {n}", lambda r, n=n: r["n"] == n) for n in dims]
    lines += table(runs, [*by_n, ("all", lambda r: True)])
    for group, fids in GROUPS.items():
        lines += ["", f"{group}:", ""]
        cols = [(f"n = {n}", lambda r, n=n, fids=fids: r["n"] == n and r["f"] in fids)
                for n in dims]
        lines += table(runs, [*cols, ("all", lambda r, fids=fids: r["f"] in fids)])
    if name == "bbob":
        lines += ["", "f7, the step ellipsoid:", ""]
        cols = [(f"n = {n}", lambda r, n=n: r["n"] == n and r["f"] == 7) for n in dims]
        lines += table(runs, [*cols, ("all", lambda r: r["f"] == 7)])
    return lines


INTRO = """# COCO: bbob and bbob-mixint

Written by `python -m studies coco page` from the runs of `python -m studies coco run`
(the peers from `studies/coco/requirements.txt`, installed with
`scripts/venv target/venv-coco studies/coco/requirements.txt`, and the plateau_free wheel
beside them). The full grid is `run --dims 5,10,20,40 --instances 1-5` and, bbob alone
having n = 2, `run --suites bbob --dims 2 --instances 1-5`; the runs below may be a part of
it, stated above each suite's tables (the dimensions and instances that fitted the time on a
shared 2-core machine).

The suites are COCO's (coco-experiment 2.8.2, `cocoex`): `bbob`, the 24 noiseless functions,
and `bbob-mixint`, the same functions with four fifths of the variables integer (of 2, 4, 8
and 16 values; COCO rounds them inside the function). These are the development instances
(1-5): the functions and instances below were looked at while the library was changed, so
they are not an unseen test set. Instances a suite ran beyond them are a second sample, in
sections of their own after the development ones. Each run has `1000 n` evaluations, starts
at COCO's `initial_solution`, has the seed of its instance number, and ends at `f_opt + 1e-8`. The
score of a run is the fraction of the 11 targets `f_opt + 10^k`, `k = 2, 1, ..., -8`, that
its best value reached; a cell is the mean over its runs (the best of a column in bold).
`f_opt` is the one COCO's own logger writes in its data files (for bbob-mixint it differs
from bbob's on some functions: f15 instance 1 is 100, not 1000).

The peers get the box as `minimize` does and a starting spread of a fifth of the mean box
width, scaled per coordinate by its width: pycma 4.5 `fmin2` with BIPOP restarts (9),
with and without `integer_variables`; `cmaes` 0.12 `CMAwM` with the integer steps, restarted
with a doubled population whenever it stops; nevergrad 1.0.12's NGOpt (its algorithm
selector) with the box as its bounds and the integer variables cast to integers, on a subset
(`run --solvers ngopt --dims 5,10 --instances 1`, its own section at the end). On bbob there is nothing to declare: the rows
with integers are the box's and are not run. `minimize` is given the budget and the target
(`target=f_opt + 1e-8`); the peers are stopped by the counter that counts every run's
evaluations alike.
"""


def second(name: str, runs: list[dict[str, Any]]) -> str:
    """The note on a suite's runs outside the development instances: the command that makes
    them and which choices they measured."""
    dims = ",".join(str(n) for n in sorted({r["n"] for r in runs}))
    instances = spans(sorted({r["instance"] for r in runs}))
    return (f" A second sample of the same functions, with other rotations, shifts and optima "
            f"(`run --suites {name} --dims {dims} --instances {instances}`, the solvers that "
            "fitted the time): instances 6-10 also measured the choice of where restarts begin "
            "([convergence.md](../convergence.md), table 2b), instances 11-15 no choice.")


POOLED = (" Every instance above, development and second sample together, for the solvers that "
          "ran both, on the functions and dimensions of the second sample.")


def problem(r: dict[str, Any]) -> tuple:
    """The problem a run solved: suite, function, dimension and instance."""
    return (r["suite"], r["f"], r["n"], r["instance"])


def common(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The runs of the problems that every solver among ``runs`` ran: a grid that a stop cut
    short is scored like with like."""
    ran: dict[str, set] = {}
    for r in runs:
        ran.setdefault(r["solver"], set()).add(problem(r))
    shared = set.intersection(*ran.values()) if ran else set()
    return [r for r in runs if problem(r) in shared]


def instance_sections(name: str, runs: list[dict[str, Any]]) -> list[str]:
    """A suite's development instances; then, when it ran others, those (a second sample) and
    every instance of the second sample's functions and dimensions pooled, for the solvers
    that ran both; each on the problems that all of its solvers ran."""
    development = common([r for r in runs if r["instance"] in DEVELOPMENT])
    others = common([r for r in runs if r["instance"] not in DEVELOPMENT])
    lines = ["", *suite_section(name, development)] if development else []
    if not others:
        return lines
    instances = spans(sorted({r["instance"] for r in others}))
    lines += ["", *suite_section(f"{name}, instances {instances}", others, second(name, others))]
    both = {r["solver"] for r in others} & {r["solver"] for r in development}
    cells = {(r["f"], r["n"]) for r in others}
    pooled = [r for r in development + others if r["solver"] in both and (r["f"], r["n"]) in cells]
    everything = spans(sorted({r["instance"] for r in pooled}))
    return lines + ["", *suite_section(f"{name}, instances {everything}", pooled, POOLED)]


def subset_section(solver: str, runs: list[dict[str, Any]]) -> list[str]:
    """Every solver on exactly the problems ``solver`` ran (a subset of the grid)."""
    ran = {problem(r) for r in runs if r["solver"] == solver}
    if not ran:
        return []
    lines = ["", f"## {SOLVERS[solver][1]}, on a subset", "",
             "Too slow for the whole grid, it ran the problems below; every solver is scored "
             "here on exactly those problems, so the cells compare like with like (they differ "
             "from the tables above, which average over more instances)."]
    for name in ("bbob-mixint", "bbob"):
        mine = [r for r in runs if r["suite"] == name and problem(r) in ran]
        if mine:
            dims = sorted({r["n"] for r in mine})
            instances = spans(sorted({r["instance"] for r in mine}))
            lines += ["", f"{name}, functions 1-24, instances {instances}:", ""]
            cols = [(f"n = {n}", lambda r, n=n: r["n"] == n) for n in dims]
            cols += [(g, lambda r, fids=fids: r["f"] in fids) for g, fids in GROUPS.items()]
            lines += table(mine, [*cols, ("all", lambda r: True)])
    return lines


def write_page(runs_dir: Path, page: Path, made_by: str | None = None) -> None:
    """The page of the runs in ``runs_dir``; ``made_by``, the commands of a page of a part of
    the grid, is stated under its title."""
    runs = [json.loads(line) for line in (runs_dir / "runs.jsonl").read_text().splitlines()]
    grid = [r for r in runs if r["solver"] not in SUBSET_SOLVERS]
    lines = INTRO.splitlines()
    if made_by:
        lines[1:1] = ["", f"This page's runs and the page itself: {made_by}."]
    for name in ("bbob-mixint", "bbob"):
        mine = [r for r in grid if r["suite"] == name]
        lines += instance_sections(name, mine)
    for solver in SUBSET_SOLVERS:
        lines += subset_section(solver, runs)
    _page.write(page, lines, runs=runs_dir)
    print(page)
