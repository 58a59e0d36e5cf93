"""``minimize`` on bbob-largescale problems over seeds (``docs/results/large-scale.md``'s
step-size rules tried): one row per run and evaluation count (1,000, 3,000,
10,000, 30,000, 100,000, 320,000 and the end), the best value minus ``f_opt`` so far and the
targets it reaches, appended to ``OUT``. The page's ``tried-seeds-bbob.csv`` is this script's
output with the wheels named there; the label names the build, nothing else differs.

    python -m studies large-scale-seeds OUT LABEL N FUNCTIONS SEEDS INSTANCES
    python -m studies large-scale-seeds seeds.csv csa 320 15 0,1,2 1

``ask_tell(x0, budget=1000 n, seed=seed, target=f_opt + 1e-8)`` from the suite's ``x0``, as
``run.py bbob`` runs it (which fixes the seed at 0), with no wall-time cap.
"""

from __future__ import annotations

import csv
import os
import sys
import time

import numpy as np

from studies.large_scale import run as ls


def run(w: "csv._writer", label: str, problem: object, fopt: float, key: list[object], seed: int) -> float:
    """One run, its rows written as it passes each evaluation count; returns best - f_opt."""
    import plateau_free

    p: object = problem
    n = len(p.initial_solution)  # type: ignore[attr-defined]
    budget = 1000 * n
    marks = sorted({b for b in (1000, 3000, 10000, 30000, 100000, 320000) if b < budget})
    x0 = np.asarray(p.initial_solution, dtype=np.float64)  # type: ignore[attr-defined]
    es = plateau_free.ask_tell(x0, budget=budget, seed=seed, target=fopt + 1e-8)
    t0, evaluations, best = time.perf_counter(), 0, np.inf

    def row() -> None:
        b = float(best - fopt)
        w.writerow([label, *key, seed, evaluations, repr(b), sum(b <= t for t in ls.TARGETS),
                    f"{time.perf_counter() - t0:.1f}"])  # fmt: skip

    while not es.done:
        xs, _ = es.ask()
        values = np.array([p(x) for x in xs])  # type: ignore[operator]
        for v in values:
            evaluations += 1
            best = min(best, float(v))
            if marks and evaluations == marks[0]:
                row()
                marks.pop(0)
        es.tell(values)
    row()
    return float(best - fopt)


def main() -> None:
    if len(sys.argv) != 7:
        sys.exit("usage: python -m studies large-scale-seeds OUT LABEL N FUNCTIONS SEEDS INSTANCES")
    import cocoex

    out, label, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    fids, seeds, insts = (ls.parse_range(a) for a in sys.argv[4:7])
    suite = cocoex.Suite("bbob-largescale", "", "")
    new = not os.path.exists(out)
    with open(out, "a", newline="") as fh:
        w = csv.writer(fh)
        if new:
            w.writerow(["label", "f", "n", "instance", "seed", "evaluations", "best_minus_opt",
                        "targets", "seconds"])  # fmt: skip
        for fid in fids:
            for inst in insts:
                fopt = ls.bbob_fopt(suite, fid, n, inst)
                for seed in seeds:
                    p = suite.get_problem_by_function_dimension_instance(fid, n, inst)
                    b = run(w, label, p, fopt, [fid, n, inst], seed)
                    p.free()
                    fh.flush()
                    print(f"{label} f{fid} n={n} instance {inst} seed {seed}: {b:.3g}", flush=True)


if __name__ == "__main__":
    main()
