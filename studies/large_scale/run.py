"""The measurements of ``docs/results/large-scale.md`` 

    scripts/large-scale            # the page's command: runs this, then writes the page

**The texture task** (ZeroGrads' task, written here in numpy): the
renderer is the identity, the parameters a ``3 x r x r`` texture (``n = 3 r^2``), and

    loss(x) = mean((x / mean(x) - 1 - (t / mean(t) - 1)) ** 2)

with ``t`` the reference: scikit-image's ``astronaut.png`` (512 x 512 RGB, shipped inside the
scikit-image wheel, ``skimage.data.astronaut()``; nothing is downloaded at run time) averaged
over ``512/r x 512/r`` blocks into ``r x r``, channels first. The start is
``0.5 + N(0, 0.05^2)`` per texel from ``numpy.random.default_rng(seed)``. Every arm evaluates
whole batches with one numpy call (``loss`` on a ``(k, n)`` array) through an ask/tell
interface, which is what makes ``10^5`` evaluations at ``n = 49,152`` fit.

The arms (one row per arm, n, seed and budget, appended to ``--out`` as runs end; a row
already there is not run again):

- ``minimize``: ``plateau_free.ask_tell(x0, budget=B, seed=seed)``, no other option;
  ``minimize-box`` with the texels' box ``bounds=[(0, 1)]`` and nothing else (its start spread
  a quarter of the box's width, every point projected onto the box); ``minimize-sigma`` with
  ``sigma0=0.25``, the peers' spread, and no box; ``minimize-lowrank`` with
  ``metric='low_rank'`` (the low-rank-plus-diagonal metric) and nothing else. One run
  at the largest budget gives every smaller one: the search does not depend on its budget, and
  its result at ``B`` is the best of the first ``B`` evaluations, which is what is recorded.
- ``paper``: the paper's loop, ``method='plateau'`` with ``sigma0=0.025, lr=0.003,
  samples=40``; its schedule depends on the budget, so one run per budget; the value is the
  returned point's (its final point, evaluated last).
- ``sepcma``: pycma's ``CMAEvolutionStrategy(x0, 0.25, {'CMA_diagonal': True})`` (separable
  CMA-ES from the first iteration on; 0.25 is a quarter of the texels' ``[0, 1]`` range, pycma's
  advice for sigma0), default population and stopping rules, pycma seed ``seed + 1`` (0 is
  pycma's "random"); best value of the first ``B`` evaluations.
- ``image``: ``plateau_free.least_squares`` on the residual vector
  ``r(x) = (x / mean(x) - 1 - (t / mean(t) - 1)) / sqrt(n)``, whose sum of squares is the loss,
  with the sparsity pattern "texel i's output depends on parameter i" (it also depends on every
  parameter through ``mean(x)``, by ``1/n`` each: the pattern drops that coupling, which the
  method's acceptance test, on the true sum of squares, keeps honest), all else default; its
  schedule depends on the budget (one run per budget); the value is the best point's.
- ``lmcma``, ``lmmaes``, ``mmes``, ``vkdcma``, ``pysepcma``: pypop7's large-scale evolution
  strategies (``pypop.py``), sigma 0.25, on the texture task and on bbob-largescale.
- ``sepcma-box`` and ``lmcma-box``, ..., ``pysepcma-box``: the same peers given the box
  ``[0, 1]^n`` as well: pycma its ``bounds`` option, pypop7's strategies the objective at the
  point projected onto the box.

Every run has a wall-time cap (``--cap`` seconds); a run that reaches it is recorded with the
evaluations it made and its best value so far, marked ``capped``.

**bbob-largescale** (``bbob`` subcommand): COCO's ``bbob-largescale`` suite from the
coco-experiment package (``cocoex``), ``minimize`` (``ask_tell(x0, budget=1000 n, seed=0)``,
no other option; ``minimize-box`` with the suite's box ``[-5, 5]^n`` and nothing else;
``minimize-lowrank`` with ``metric='low_rank'``) against sep-CMA-ES (pycma, ``CMA_diagonal=True``, sigma0 2, seed 1, with
IPOP-free default stopping: a run that stops early leaves budget unused), at ``1000 n``
evaluations (both stop at ``f_opt + 1e-8``), recording the fraction of the 11 targets ``f_opt + 10^k``, ``k = 2, 1, ..., -8``,
reached, as ``docs/results/compare.md`` counts them.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import time
from dataclasses import dataclass
from typing import Callable, Iterator, Optional

import numpy as np
from numpy.typing import NDArray

Vector = NDArray[np.float64]
Batch = Callable[[NDArray[np.float64]], Vector]

TEXTURE_COLUMNS = [
    "arm", "n", "seed", "budget", "evaluations", "loss", "start_loss", "seconds", "capped",
]  # fmt: skip
BBOB_COLUMNS = [
    "method", "function", "n", "instance", "evaluations", "best_minus_opt", "targets_reached",
    "seconds", "capped",
]  # fmt: skip
TARGETS = [10.0**k for k in range(2, -9, -1)]
# pypop7's large-scale strategies (``pypop.py``), by arm name.
PYPOP = ("lmcma", "lmmaes", "mmes", "vkdcma", "pysepcma")
# The peers given the box [0, 1] as well: pycma's own bound handling (``bounds``), and for
# pypop7's strategies, which take no box, the objective of the point projected onto it (the
# repair ``minimize`` makes when given ``bounds``).
BOXED = ("sepcma-box", *(f"{arm}-box" for arm in PYPOP))


def reference(r: int) -> Vector:
    """The astronaut averaged into ``r x r`` blocks, channels first, flattened (``3 r^2``)."""
    from skimage import data  # the only use of scikit-image: its shipped image

    image = data.astronaut().astype(np.float64) / 255.0  # (512, 512, 3)
    side = image.shape[0]
    if side % r:
        raise ValueError(f"r = {r} must divide the image's side {side}")
    b = side // r
    blocks = image.reshape(r, b, r, b, 3).mean(axis=(1, 3))  # (r, r, 3)
    return np.ascontiguousarray(blocks.transpose(2, 0, 1)).ravel()


@dataclass
class Texture:
    """The texture task at ``n = 3 r^2``: the normalised reference and the batched loss."""

    target: Vector  # t / mean(t) - 1

    @classmethod
    def of_size(cls, n: int) -> "Texture":
        r = math.isqrt(n // 3)
        if 3 * r * r != n:
            raise ValueError(f"n = {n} is not 3 r^2")
        t = reference(r)
        return cls(t / t.mean() - 1.0)

    @property
    def n(self) -> int:
        return int(self.target.size)

    def loss(self, xs: NDArray[np.float64]) -> Vector:
        """The loss of each row of ``xs`` (``(k, n)``); a row of mean 0 is worth 1e300.

        Expanded, ``|x/m - u|^2 = |x|^2/m^2 - 2 x.u/m + |u|^2`` with ``u = 1 + target``:
        three reads of ``xs`` and no temporary array (twice as fast as the direct form at
        n = 49,152); the rounding of the expansion is about 1e-16 of ``|u|^2/n ~ 1``, far
        below every loss on the page.
        """
        xs = np.atleast_2d(xs)
        u = self.target + 1.0
        s = xs.sum(axis=1)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            m = s / self.n
            v = (np.einsum("ij,ij->i", xs, xs) / (m * m) - 2.0 * (xs @ u) / m + u @ u) / self.n
        out: Vector = np.where(np.isfinite(v), np.maximum(v, 0.0), 1e300)
        return out

    def residuals(self, x: Vector) -> Vector:
        """The residual vector whose sum of squares is ``loss(x)``."""
        r: Vector = (x / x.mean() - 1.0 - self.target) / math.sqrt(self.n)
        return r

    def start(self, seed: int) -> Vector:
        rng = np.random.default_rng(seed)
        return 0.5 + rng.normal(0.0, 0.05, self.n)


class Recorder:
    """The best value of the first ``B`` evaluations, for every ``B`` of ``budgets``."""

    def __init__(self, budgets: list[int]) -> None:
        self.budgets = sorted(budgets)
        self.best = math.inf
        self.evaluations = 0
        self.at: dict[int, float] = {}

    def see(self, values: Vector) -> None:
        for b in self.budgets:
            if b not in self.at and self.evaluations + values.size >= b:
                k = b - self.evaluations
                self.at[b] = min(self.best, float(values[:k].min()))
        self.best = min(self.best, float(values.min()))
        self.evaluations += int(values.size)

    def values(self, capped: bool, fill: bool = True) -> dict[int, float]:
        """The best value at each budget reached. With ``fill``, a run that stopped early keeps
        its best for the larger budgets; a capped run shows its best at the largest."""
        values = dict(self.at)
        if fill and not capped:
            for b in self.budgets:
                values.setdefault(b, self.best)
        if capped:
            values.setdefault(max(self.budgets), self.best)
        return values


@dataclass
class Outcome:
    """One run: the value at each budget reached (or the last value, when capped)."""

    values: dict[int, float]
    evaluations: int
    seconds: float
    capped: bool


# The options of each ``minimize`` arm on the texture task: none; the texels' box (which also
# sets the start spread, a quarter of its width); the peers' one spread, without the box; the
# low-rank-plus-diagonal metric.
MINIMIZE_ARMS: dict[str, dict[str, object]] = {
    "minimize": {},
    "minimize-box": {"bounds": [(0.0, 1.0)]},
    "minimize-sigma": {"sigma0": 0.25},
    "minimize-lowrank": {"metric": "low_rank"},
}
# The same on bbob-largescale, whose box is [-5, 5]^n.
BBOB_MINIMIZE: dict[str, dict[str, object]] = {
    "minimize": {},
    "minimize-box": {"bounds": [(-5.0, 5.0)]},
    "minimize-lowrank": {"metric": "low_rank"},
    "minimize-full": {"metric": "full"},
}


def run_minimize(
    task: Texture, x0: Vector, budgets: list[int], seed: int, cap: float, arm: str = "minimize"
) -> Outcome:
    import plateau_free

    rec = Recorder(budgets)
    t0 = time.perf_counter()
    es = plateau_free.ask_tell(x0, budget=max(budgets), seed=seed, **MINIMIZE_ARMS[arm])
    capped = False
    while not es.done:
        if time.perf_counter() - t0 > cap:
            capped = True
            break
        xs, _ = es.ask()
        v = task.loss(xs)
        rec.see(v)
        es.tell(v)
    seconds = time.perf_counter() - t0
    if not capped and not math.isclose(es.result.fun, rec.best, rel_tol=0, abs_tol=0):
        raise AssertionError(f"minimize returned {es.result.fun}, best evaluated {rec.best}")
    return Outcome(rec.values(capped, fill=False), rec.evaluations, seconds, capped)


def run_paper(task: Texture, x0: Vector, budget: int, seed: int, cap: float) -> Outcome:
    import plateau_free

    t0 = time.perf_counter()
    es = plateau_free.ask_tell(
        x0, method="plateau", budget=budget, sigma0=0.025, lr=0.003, samples=40, seed=seed
    )
    evaluations, last = 0, math.inf
    capped = False
    while not es.done:
        if time.perf_counter() - t0 > cap:
            capped = True
            break
        xs, _ = es.ask()
        v = task.loss(xs)
        evaluations += int(v.size)
        last = float(v[-1])
        es.tell(v)
    value = last if capped else float(es.result.fun)
    return Outcome({budget: value}, evaluations, time.perf_counter() - t0, capped)


def run_sepcma(
    task: Texture, x0: Vector, budgets: list[int], seed: int, cap: float, box: bool = False
) -> Outcome:
    import cma

    rec = Recorder(budgets)
    t0 = time.perf_counter()
    opts = {"CMA_diagonal": True, "seed": seed + 1, "verbose": -9, "maxfevals": max(budgets)}
    if box:
        opts["bounds"] = [0.0, 1.0]
    es = cma.CMAEvolutionStrategy(x0, 0.25, opts)
    capped = False
    while not es.stop() and rec.evaluations < max(budgets):
        if time.perf_counter() - t0 > cap:
            capped = True
            break
        xs = es.ask()
        # pycma's bound transform hands out points in the box; the clip only guards that.
        v = task.loss(np.clip(np.asarray(xs), 0.0, 1.0) if box else np.asarray(xs))
        rec.see(v)
        es.tell(xs, v.tolist())
    return Outcome(rec.values(capped), rec.evaluations, time.perf_counter() - t0, capped)


def run_image(task: Texture, x0: Vector, budget: int, seed: int, cap: float) -> Outcome:
    import plateau_free

    t0 = time.perf_counter()
    calls, best = 0, math.inf

    class Capped(Exception):
        pass

    def fun(x: Vector) -> Vector:
        # The best sum of squares seen is the method's best point's (it returns the best
        # point evaluated): what a capped run reports.
        nonlocal calls, best
        if time.perf_counter() - t0 > cap:
            raise Capped
        calls += 1
        r = task.residuals(x)
        best = min(best, float(r @ r))
        return r

    n = task.n
    pattern = np.stack([np.arange(n), np.arange(n)], axis=1)
    try:
        res = plateau_free.least_squares(fun, x0, budget=budget, sparsity=pattern, seed=seed)
    except Capped:
        return Outcome({budget: best}, calls, time.perf_counter() - t0, True)
    return Outcome({budget: float(res.fun)}, int(res.nfev), time.perf_counter() - t0, False)


def done_rows(path: str) -> set[tuple[str, ...]]:
    if not os.path.exists(path):
        return set()
    with open(path) as f:
        return {(r["arm"], r["n"], r["seed"], r["budget"]) for r in csv.DictReader(f)}


def append(path: str, columns: list[str], rows: list[dict[str, object]]) -> None:
    new = not os.path.exists(path)
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        if new:
            w.writeheader()
        w.writerows(rows)


def texture_main(a: argparse.Namespace) -> None:
    budgets = sorted(int(float(b)) for b in a.budgets.split(","))
    seeds = [int(s) for s in a.seeds.split(",")]
    for n in [int(v) for v in a.n.split(",")]:
        task = Texture.of_size(n)
        for seed in seeds:
            x0 = task.start(seed)
            start_loss = float(task.loss(x0[None, :])[0])
            for arm in a.arms.split(","):
                done = done_rows(a.out)
                todo = [b for b in budgets if (arm, str(n), str(seed), str(b)) not in done]
                if not todo:
                    continue
                for outcome, wanted in runs(arm, task, x0, todo, seed, a.cap):
                    rows = [
                        dict(arm=arm, n=n, seed=seed, budget=b, evaluations=outcome.evaluations,
                             loss=repr(outcome.values.get(b, math.nan)), start_loss=repr(start_loss),
                             seconds=f"{outcome.seconds:.1f}", capped=int(outcome.capped))
                        for b in wanted
                    ]  # fmt: skip
                    append(a.out, TEXTURE_COLUMNS, rows)
                    print(
                        f"{arm:9} n={n:6} seed={seed} {wanted} evals={outcome.evaluations} "
                        f"{[outcome.values.get(b) for b in wanted]} start={start_loss:.3g} "
                        f"{outcome.seconds:.0f}s{' CAPPED' if outcome.capped else ''}",
                        flush=True,
                    )


def runs(
    arm: str, task: Texture, x0: Vector, budgets: list[int], seed: int, cap: float
) -> Iterator[tuple[Outcome, list[int]]]:
    """The runs of one arm for the budgets not yet measured, smallest first."""
    if arm in MINIMIZE_ARMS:
        yield run_minimize(task, x0, budgets, seed, cap, arm), budgets
    elif arm in ("sepcma", "sepcma-box"):
        yield run_sepcma(task, x0, budgets, seed, cap, arm == "sepcma-box"), budgets
    elif arm == "paper":
        for b in budgets:
            yield run_paper(task, x0, b, seed, cap), [b]
    elif arm == "image":
        for b in budgets:
            yield run_image(task, x0, b, seed, cap), [b]
    elif arm in PYPOP or arm in BOXED:
        from studies.large_scale import pypop

        yield pypop.texture(arm, task, x0, budgets, seed, cap), budgets
    else:
        raise ValueError(f"arm = {arm!r}: expected one of {list(MINIMIZE_ARMS)}, paper, sepcma, image, {PYPOP} or {BOXED}")


def bbob_minimize(
    problem: object, budget: int, target: float, cap: float, arm: str = "minimize"
) -> tuple[int, bool]:
    import plateau_free

    p: object = problem
    x0 = np.asarray(p.initial_solution, dtype=np.float64)  # type: ignore[attr-defined]
    es = plateau_free.ask_tell(x0, budget=budget, seed=0, target=target, **BBOB_MINIMIZE[arm])
    t0, evaluations = time.perf_counter(), 0
    while not es.done:
        if time.perf_counter() - t0 > cap:
            return evaluations, True
        xs, _ = es.ask()
        v = np.array([p(x) for x in xs])  # type: ignore[operator]
        evaluations += len(v)
        es.tell(v)
    return evaluations, False


def bbob_sepcma(problem: object, budget: int, target: float, cap: float) -> tuple[int, bool]:
    import cma

    p: object = problem
    x0 = np.asarray(p.initial_solution, dtype=np.float64)  # type: ignore[attr-defined]
    opts = {"CMA_diagonal": True, "seed": 1, "verbose": -9, "maxfevals": budget, "ftarget": target}
    es = cma.CMAEvolutionStrategy(x0, 2.0, opts)
    t0, evaluations = time.perf_counter(), 0
    while not es.stop() and evaluations < budget:
        if time.perf_counter() - t0 > cap:
            return evaluations, True
        xs = es.ask()
        xs = xs[: budget - evaluations]
        v = [p(x) for x in xs]  # type: ignore[operator]
        evaluations += len(v)
        if len(xs) < es.popsize:
            break
        es.tell(xs, v)
    return evaluations, False


def bbob_fopt(suite: object, fid: int, n: int, inst: int) -> float:
    """The optimal value of a problem: its value at the optimum that cocoex writes
    (``Problem._best_parameter('print')`` writes ``._bbob_problem_best_parameter.txt`` into the
    working directory, a temporary one here), on a fresh copy of the problem."""
    import tempfile

    q = suite.get_problem_by_function_dimension_instance(fid, n, inst)  # type: ignore[attr-defined]
    here = os.getcwd()
    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)
        try:
            q._best_parameter("print")
            xopt = np.loadtxt("._bbob_problem_best_parameter.txt")
        finally:
            os.chdir(here)
    fopt = float(q(xopt))
    q.free()
    return fopt


def bbob_main(a: argparse.Namespace) -> None:
    import cocoex

    dims = [int(d) for d in a.dims.split(",")]
    functions = parse_range(a.functions)
    instances = parse_range(a.instances)
    done: set[tuple[str, ...]] = set()
    if os.path.exists(a.out):
        with open(a.out) as f:
            done = {(r["method"], r["function"], r["n"], r["instance"]) for r in csv.DictReader(f)}
    suite = cocoex.Suite("bbob-largescale", "", "")
    for n in dims:
        for fid in functions:
            for inst in instances:
                for method in a.methods.split(","):
                    if (method, str(fid), str(n), str(inst)) in done:
                        continue
                    bbob_run(suite, method, fid, n, inst, a)


def bbob_run(suite: object, method: str, fid: int, n: int, inst: int, a: argparse.Namespace) -> None:
    """One run on a fresh problem, appended to ``a.out``."""
    fopt = bbob_fopt(suite, fid, n, inst)
    p = suite.get_problem_by_function_dimension_instance(fid, n, inst)  # type: ignore[attr-defined]
    t0 = time.perf_counter()
    # Every method stops at the last target, f_opt + 1e-8 (as docs/results/compare.md's runs do).
    if method in PYPOP:
        from studies.large_scale import pypop

        evaluations, capped = pypop.bbob(method, p, 1000 * n, fopt + 1e-8, a.cap)
    elif method in BBOB_MINIMIZE:
        evaluations, capped = bbob_minimize(p, 1000 * n, fopt + 1e-8, a.cap, method)
    else:
        evaluations, capped = bbob_sepcma(p, 1000 * n, fopt + 1e-8, a.cap)
    seconds = time.perf_counter() - t0
    best_value = float(p.best_observed_fvalue1)
    p.free()
    best = best_value - fopt
    reached = sum(best <= t for t in TARGETS)
    row = dict(method=method, function=fid, n=n, instance=inst, evaluations=evaluations,
               best_minus_opt=repr(best), targets_reached=reached, seconds=f"{seconds:.1f}",
               capped=int(capped))  # fmt: skip
    append(a.out, BBOB_COLUMNS, [row])
    print(f"bbob {method:8} f{fid:<2} n={n:4} best-opt {best:.3g} {reached}/11 {seconds:.1f}s",
          flush=True)  # fmt: skip


def overhead_main(a: argparse.Namespace) -> None:
    """``minimize``'s own time per evaluation at ``n`` (its asks and tells, without the
    objective) beside the time numpy takes to draw one standard normal vector of ``n``
    (the cost of drawing the sample), appended to ``--out``."""
    import plateau_free

    n = a.n
    rng = np.random.default_rng(0)
    x0 = 0.5 + rng.normal(0.0, 0.05, n)
    es = plateau_free.ask_tell(x0, budget=10**9, seed=0)
    own, evaluations = 0.0, 0
    for _ in range(a.generations):
        t0 = time.perf_counter()
        xs, _ = es.ask()
        own += time.perf_counter() - t0
        v = np.sum((xs - 0.5) ** 2, axis=1)  # any objective: its time is not counted
        t0 = time.perf_counter()
        es.tell(v)
        own += time.perf_counter() - t0
        evaluations += len(v)
    t0 = time.perf_counter()
    for _ in range(evaluations):
        rng.standard_normal(n)
    draw = (time.perf_counter() - t0) / evaluations
    row = dict(n=n, evaluations=evaluations, minimize_seconds=repr(own / evaluations),
               normal_draw_seconds=repr(draw))  # fmt: skip
    append(a.out, list(row), [row])
    print(f"overhead n={n}: minimize {own / evaluations:.3g} s/evaluation, numpy normals "
          f"{draw:.3g} s", flush=True)  # fmt: skip


def parse_range(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out.extend(range(int(lo), int(hi or lo) + 1))
    return out


def main(argv: Optional[list[str]] = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    t = sub.add_parser("texture", help="the texture task")
    t.add_argument("--n", default="768,3072,12288,49152,196608")
    t.add_argument("--budgets", default="1e4,1e5")
    t.add_argument("--seeds", default="0,1,2")
    t.add_argument("--arms", default="minimize,paper,sepcma,image")
    t.add_argument("--cap", type=float, default=300.0, help="wall seconds per run")
    t.add_argument("--out", required=True)
    b = sub.add_parser("bbob", help="bbob-largescale")
    b.add_argument("--dims", default="20,40,80,160")
    b.add_argument("--functions", default="1-24")
    b.add_argument("--instances", default="1")
    b.add_argument("--methods", default="minimize,sepcma")
    b.add_argument("--cap", type=float, default=120.0, help="wall seconds per run")
    b.add_argument("--out", required=True)
    o = sub.add_parser("overhead", help="minimize's time per evaluation, without the objective")
    o.add_argument("--n", type=int, default=49152)
    o.add_argument("--generations", type=int, default=100)
    o.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    if a.what == "texture":
        texture_main(a)
    elif a.what == "bbob":
        bbob_main(a)
    else:
        overhead_main(a)


if __name__ == "__main__":
    main()
