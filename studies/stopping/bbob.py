"""bbob with `plateau_free.minimize`'s defaults: the targets reached and the evaluations spent.

    pip install coco-experiment==2.8.2      # and the plateau_free wheel to measure
    python -m studies stopping-bbob run OUT.csv 0 1 2 3 4   # seeds; ~1 min a seed
    python -m studies stopping-bbob run OUT.csv --patience 0 0 1 2 3 4   # the budget alone
    python -m studies stopping-bbob summary A.csv B.csv      # score and evaluations
    python -m studies stopping-bbob page OUT.md LABEL=A.csv[+B.csv] ...   # the results page

Every problem of the suite at n = 2, 5, 10, 20 (instances 1-5) gets `minimize(f, x0,
budget=1000 n, seed=s)` from the suite's initial solution. A run reaches target t of the 51
targets 10^2, 10^1.8, ..., 10^-8 when its best value within the budget is at most t above
the optimum; the score is the fraction over targets and runs. `evaluations` is what the run
spent: below the budget when a stop rule ended it.
"""
import collections
import csv
import os
import sys
import tempfile

import numpy as np

TARGETS = [10 ** (2 - k / 5) for k in range(51)]


def optimum(problem):
    """The problem's optimal value: its optimum, which cocoex writes to a file in the cwd."""
    here = os.getcwd()
    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)
        try:
            problem._best_parameter("print")
            xopt = np.atleast_1d(np.loadtxt("._bbob_problem_best_parameter.txt"))
        finally:
            os.chdir(here)
    return problem(xopt)


def run(out, seeds, patience=None):
    """One CSV row per problem and seed; ``patience`` is ``minimize``'s option (``None``: its
    default)."""
    import cocoex
    import plateau_free as pf

    suite = cocoex.Suite("bbob", "", "dimensions: 2,5,10,20 instance_indices: 1-5")
    with open(out, "w") as fh:
        fh.write("function,n,instance,seed,evaluations,budget,targets,precision\n")
        for problem in suite:
            n, fopt = problem.dimension, optimum(problem)
            budget = 1000 * n
            for seed in seeds:
                best, count = [np.inf], [0]

                def f(x):
                    v = problem(x)
                    count[0] += 1
                    if count[0] <= budget and v < best[0]:
                        best[0] = v
                    return v

                options = {} if patience is None else {"patience": patience}
                pf.minimize(f, np.array(problem.initial_solution), budget=budget, seed=seed,
                            **options)
                reached = sum(best[0] - fopt <= t for t in TARGETS)
                row = (problem.id_function, n, problem.id_instance, seed, count[0], budget)
                fh.write(",".join(map(str, row + (reached, best[0] - fopt))) + "\n")


def summary(paths):
    for path in paths:
        rows = list(csv.DictReader(open(path)))
        reached = sum(int(r["targets"]) for r in rows)
        spent = sum(int(r["evaluations"]) for r in rows) / sum(int(r["budget"]) for r in rows)
        per = collections.Counter()
        for r in rows:
            per[int(r["function"])] += int(r["targets"])
        print(f"{path}: score {reached / (51 * len(rows)):.4f} ({reached} of {51 * len(rows)}),"
              f" {spent:.3f} of the budget; per function {dict(sorted(per.items()))}")


def scores(paths):
    """Targets reached, runs, the share of the budget spent, and targets per function, of the
    runs in ``paths`` taken together."""
    rows = [r for path in paths for r in csv.DictReader(open(path))]
    per = collections.Counter()
    for r in rows:
        per[int(r["function"])] += int(r["targets"])
    spent = sum(int(r["evaluations"]) for r in rows) / sum(int(r["budget"]) for r in rows)
    return sum(per.values()), len(rows), spent, per


def page(out, arms):
    """docs/results/stopping-bbob.md: one column per arm (``LABEL=A.csv+B.csv``): the score,
    the targets reached, the share of the budget spent, and the score per function."""
    from studies import _page

    labels, results = [], []
    for arm in arms:
        label, files = arm.split("=", 1)
        labels.append(label)
        results.append(scores(files.split("+")))
    functions = sorted(set().union(*(r[3] for r in results)))
    rows = [["score"] + [f"{r[0] / (51 * r[1]):.4f}" for r in results],
            ["targets reached"] + [f"{r[0]} of {51 * r[1]}" for r in results],
            ["share of the budget spent"] + [f"{r[2]:.3f}" for r in results]]
    rows += [[f"f{k}"] + [f"{r[3][k] / (51 * r[1] / len(functions)):.3f}" for r in results]
             for k in functions]
    text = ["# When a run is done: bbob", "",
            "`minimize(f, x0, budget=1000 n, seed=s)` on every problem of COCO's bbob suite "
            "(coco-experiment 2.8.2) at n = 2, 5, 10, 20, instances 1-5, from the suite's initial "
            "solution. A run reaches target t of the 51 targets 10^2, 10^1.8, ..., 10^-8 when its "
            "best value within the budget is at most t above the optimum; the score is the "
            "fraction over targets and runs; the share of the budget is what the runs spent "
            "(below 1 when a stop rule ended them). Per function: the score over its runs.", "",
            f"Written by `python -m studies stopping-bbob page {out} {' '.join(arms)}`, from the "
            "runs of `python -m studies stopping-bbob run OUT.csv [--patience K] SEEDS` (one CSV "
            "per arm).", ""]
    text += _page.table(["", *labels], rows)
    _page.write(out, text)


if __name__ == "__main__":
    if {"-h", "--help"} & set(sys.argv[1:]):
        sys.exit(__doc__)
    if len(sys.argv) >= 3 and sys.argv[1] == "run":
        rest, patience = sys.argv[3:], None
        if rest[:1] == ["--patience"] and len(rest) >= 2:
            patience, rest = int(rest[1]), rest[2:]
        run(sys.argv[2], [int(s) for s in rest] or [0], patience)
    elif len(sys.argv) >= 3 and sys.argv[1] == "summary":
        summary(sys.argv[2:])
    elif len(sys.argv) >= 4 and sys.argv[1] == "page":
        page(sys.argv[2], sys.argv[3:])
    else:
        sys.exit(__doc__)
