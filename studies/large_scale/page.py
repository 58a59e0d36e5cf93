"""Writes ``docs/results/large-scale.md`` (and its plot) from the csv files of
``studies/large_scale/run.py`` in a run directory.

    python -m studies large-scale-page OUT PAGE COMMAND

``OUT`` holds ``texture-*.csv`` and ``bbob*.csv``; ``PAGE`` is the page to write (the plot goes
beside it, same name with ``.png``); ``COMMAND`` is the command the page names.
"""

from __future__ import annotations

import csv
import glob
import math
import os
import sys
from collections import defaultdict
from statistics import median
from typing import Iterable

from studies import _page

SIZES = [768, 3072, 12288, 49152, 196608]
BUDGETS = [10_000, 100_000, 1_000_000]
SEEDS = [0, 1, 2]
ARMS = {
    "minimize": "`minimize` (default)",
    "minimize-box": "`minimize` (the box [0, 1])",
    "minimize-sigma": "`minimize` (sigma0 0.25)",
    "paper": "paper loop (sigma0 0.025, lr 0.003, N 40)",
    "sepcma": "sep-CMA-ES (pycma)",
    "image": "image method (`least_squares`)",
}
# pypop7's large-scale strategies (``pypop.py``), the yardsticks' table.
PEERS = {
    "lmcma": "LM-CMA",
    "lmmaes": "LM-MA-ES",
    "mmes": "MMES",
    "vkdcma": "VkD-CMA",
    "pysepcma": "sep-CMA-ES (pypop7)",
}
ALL = {**ARMS, **PEERS}
# The peers given the box [0, 1] (``run.py``'s ``BOXED``): the table of every arm given the box.
BOXED = {"sepcma-box": "sep-CMA-ES (pycma, its `bounds`)"} | {f"{a}-box": label for a, label in PEERS.items()}
LABELS = {**ALL, **BOXED}
# The arms of the yardsticks' table and of the table of every arm given the box.
YARDSTICK_ARMS = ["minimize", "minimize-box", "minimize-sigma", "sepcma", *PEERS]
BOXED_ARMS = ["minimize-box", *BOXED]
Row = dict[str, str]


def read(paths: Iterable[str]) -> list[Row]:
    rows: list[Row] = []
    for path in paths:
        with open(path) as f:
            rows.extend(csv.DictReader(f))
    return rows


def fmt(v: float) -> str:
    if math.isnan(v):
        return "n/a"
    if v == 0:
        return "0"
    if 0.01 <= abs(v) < 1000:
        return f"{v:.3g}"
    return f"{v:.1e}"


def texture_cells(rows: list[Row]) -> dict[tuple[str, int, int], list[Row]]:
    cells: dict[tuple[str, int, int], list[Row]] = defaultdict(list)
    for r in rows:
        cells[(r["arm"], int(r["n"]), int(r["budget"]))].append(r)
    return cells


def cell_text(runs: list[Row]) -> tuple[str, float]:
    """The median loss over the seeds that ran (all of 0-2, or it says which), with marks:
    how many runs the wall-time cap stopped before this budget, and how many ended worse than
    their start."""
    by_seed = {int(r["seed"]): r for r in runs if not math.isnan(float(r["loss"]))}
    seeds = [s for s in SEEDS if s in by_seed]
    if not seeds:
        capped = [r for r in runs if r["capped"] == "1"]
        if capped:
            evals = sorted(int(r["evaluations"]) for r in capped)
            return f"n/a (capped before it: {len(capped)} runs, at {fmt(evals[0])}-{fmt(evals[-1])} evaluations)", math.nan
        return "", math.nan
    losses = [float(by_seed[s]["loss"]) for s in seeds]
    med = median(losses)
    marks = ""
    if len(seeds) < len(SEEDS):
        plural = "s" if len(seeds) > 1 else ""
        marks += f" (seed{plural} {', '.join(map(str, seeds))} only)"
    b = int(runs[0]["budget"])
    capped = [by_seed[s] for s in seeds if by_seed[s]["capped"] == "1" and int(by_seed[s]["evaluations"]) < b]
    if capped:
        evals = sorted(int(r["evaluations"]) for r in capped)
        marks += f" (capped: {len(capped)} of {len(seeds)}, at {fmt(evals[0])}-{fmt(evals[-1])} evaluations)"
    worse = sum(float(by_seed[s]["loss"]) > float(by_seed[s]["start_loss"]) for s in seeds)
    if worse:
        marks += f", worse than the start in {worse} of {len(seeds)}"
    return fmt(med) + "\u0000" + marks, med


def in_grid(arm: str, n: int, budget: int) -> bool:
    """Whether ``scripts/large-scale`` runs this cell: 10^4 and 10^5 everywhere (the image
    method's 10^5 up to n = 3,072), 10^6 at n = 768 (not for the image method); ``minimize``
    with sigma0 0.25 at n <= 3,072; pypop7's strategies, with or without the box, at 10^4 at
    every size and at 10^5 up to n = 12,288 (pycma's with the box as without)."""
    if arm in PEERS or arm in BOXED and arm != "sepcma-box":
        return budget == 10_000 or budget == 100_000 and n <= 12288
    if arm == "minimize-sigma" and n > 3072:
        return False
    if budget == 1_000_000:
        return n == 768 and arm != "image"
    return not (arm == "image" and budget == 100_000 and n > 3072)


def bold(text: str) -> str:
    number, _, marks = text.partition("\u0000")
    return f"**{number}**" + marks


def texture_table(rows: list[Row], arms: list[str], sizes: list[int]) -> tuple[list[str], list[str]]:
    """The table of ``arms`` at ``sizes`` (bold: the lowest of the scalar arms, every arm but
    the image method), and the cells of the grid that did not run."""
    cells = texture_cells(rows)
    lines = [
        "| n | evaluations | start (median) | " + " | ".join(LABELS[a] for a in arms) + " |",
        "|---|---|---|" + "---|" * len(arms),
    ]
    missing: list[str] = []
    for n in sizes:
        for b in BUDGETS:
            texts, values = [], []
            for arm in arms:
                text, value = cell_text(cells.get((arm, n, b), []))
                if not text and in_grid(arm, n, b):
                    missing.append(f"{LABELS[arm]}{' (the box)' if arm in BOXED else ''}, n = {n:,}, {b:.0e} evaluations")
                texts.append(text)
                values.append(value)
            if all(not t for t in texts):
                continue
            starts = [float(r["start_loss"]) for arm in arms for r in cells.get((arm, n, b), [])]
            scalar = [v for a, v in zip(arms, values) if a != "image"]
            best = min((v for v in scalar if not math.isnan(v)), default=math.nan)
            shown = [bold(t) if t and v == best else (t or "not run") for t, v in zip(texts, values)]
            shown = [t.replace("\u0000", "") for t in shown]
            start = fmt(median(sorted(set(starts)))) if starts else "n/a"
            lines.append(f"| {n:,} | {b:.0e} | {start} | " + " | ".join(shown) + " |")
    return lines, missing


def standing(rows: list[Row], arm: str, peers: list[str]) -> str:
    """Where ``arm``'s median is the lowest of ``peers``' and where it is not, over the rows in
    which it and at least one of them ran."""
    cells = texture_cells(rows)
    behind, rows_seen = [], 0
    for n in SIZES:
        for b in BUDGETS:
            own = cell_text(cells.get((arm, n, b), []))[1]
            theirs = {p: cell_text(cells.get((p, n, b), []))[1] for p in peers}
            theirs = {p: v for p, v in theirs.items() if not math.isnan(v)}
            if math.isnan(own) or not theirs:
                continue
            rows_seen += 1
            leader = min(theirs, key=lambda p: theirs[p])
            if theirs[leader] < own:
                behind.append(f"n = {n:,} with {b:.0e} evaluations ({fmt(own)} against {LABELS[leader]}'s {fmt(theirs[leader])})")
    text = f"{LABELS[arm]} is at or below every peer in {rows_seen - len(behind)} of the {rows_seen} rows where both ran"
    return text + ("; behind in " + "; ".join(behind) + "." if behind else ".")


def never_worse(rows: list[Row]) -> list[str]:
    lines = []
    for arm in LABELS:
        runs = [r for r in rows if r["arm"] == arm and r["capped"] == "0"]
        worse = [r for r in runs if float(r["loss"]) > float(r["start_loss"])]
        if not runs:
            continue
        text = f"- {LABELS[arm]}{' given the box' if arm in BOXED else ''}: {len(runs) - len(worse)} of {len(runs)} finished runs at or below the start"
        if worse:
            text += ": worse in " + ", ".join(
                f"n = {int(r['n']):,} seed {r['seed']} at {int(r['budget']):.0e} ({fmt(float(r['loss']))} > {fmt(float(r['start_loss']))})"
                for r in worse
            )
        lines.append(text)
    return lines


def seconds_per_evaluation(rows: list[Row]) -> list[str]:
    lines = ["| n | " + " | ".join(ALL.values()) + " |", "|---|" + "---|" * len(ALL)]
    for n in SIZES:
        cells = []
        for arm in ALL:
            runs = [r for r in rows if r["arm"] == arm and int(r["n"]) == n and int(r["evaluations"]) > 0]
            # One row per run: a run that gave several budgets is listed once per budget.
            seen = {(r["seed"], r["evaluations"], r["seconds"]) for r in runs}
            rates = [float(s) / int(e) for _, e, s in seen]
            cells.append(f"{median(rates):.2e}" if rates else "not run")
        lines.append(f"| {n:,} | " + " | ".join(cells) + " |")
    return lines


def plot(rows: list[Row], path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cells = texture_cells(rows)
    fig, axes = plt.subplots(1, len(SIZES), figsize=(4 * len(SIZES), 3.6))
    for ax, n in zip(axes, SIZES):
        for arm, label in ALL.items():
            xs, ys = [], []
            for b in BUDGETS:
                _, value = cell_text(cells.get((arm, n, b), []))
                if not math.isnan(value):
                    xs.append(b)
                    ys.append(max(value, 1e-16))  # the image method's 1e-34: drawn at 1e-16
            if xs:
                ax.plot(xs, ys, marker="o", label=label.replace("`", ""))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"n = {n:,}")
        ax.set_xlabel("evaluations")
    axes[0].set_ylabel("loss (median of seeds; 1e-16 = below)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def csa_time_scale(n: int) -> tuple[int, float, float, float]:
    """The default population, and the fewest evaluations per e-fold decrease of sigma under
    cumulative step-size adaptation (its log-step is ``cs / ds (|p_s| / chi_n - 1) >= -cs / ds``
    per generation), under the median success rule (``s / d >= -1 / d`` per generation,
    ``d = 2 (n - 1) / n``), with the constants of ``src/method/adaptive/gaussian.rs``, and under
    two-point step-size adaptation (``s / d >= -1 / d``, ``d = 0.7 + 2 ln n``, pycma's damping)."""
    lam = 4 + int(3 * math.log(n))
    mu = lam // 2
    raw = [math.log((lam + 1) / 2) - math.log(i + 1) for i in range(mu)]
    mueff = sum(raw) ** 2 / sum(w * w for w in raw)
    cs = (mueff + 2) / (n + mueff + 5)
    ds = 1 + 2 * max(0.0, math.sqrt((mueff - 1) / (n + 1)) - 1) + cs
    tpa = 0.7 + 2 * math.log(n) + 2 * math.log(max(1, lam - n))
    return lam, lam * ds / cs, lam * max(2 * (n - 1) / n, 1.0), lam * tpa


def time_scales() -> list[str]:
    lines = [
        "| n | population | evaluations per e-fold of sigma, at least: cumulative step-size adaptation | median success rule | two-point adaptation |",
        "|---|---|---|---|---|",
    ]
    for n in [20, 160] + SIZES:
        lam, csa, msr, tpa = csa_time_scale(n)
        lines.append(f"| {n:,} | {lam} | {csa:,.0f} | {msr:,.0f} | {tpa:,.0f} |")
    return lines


def tried_table(default: list[Row], tried: dict[str, list[Row]]) -> list[str]:
    """``minimize`` as it is (the default) beside the variants tried, median over seeds, per
    size and budget."""
    cells = {label: texture_cells(rows) for label, rows in tried.items()}
    base = texture_cells(default)
    head = "| n | evaluations | default (TPA warm-up, back to the start if it beat nothing, then CSA) | " + " | ".join(f"tried: {k}" for k in tried) + " |"
    lines = [head, "|---|---|---|" + "---|" * len(tried)]
    for n in SIZES:
        for budget in BUDGETS:
            texts = [cell_text(base.get(("minimize", n, budget), []))[0]]
            texts += [cell_text(c.get(("minimize", n, budget), []))[0] for c in cells.values()]
            if any(texts[1:]):
                shown = [t.replace("\u0000", "") or "not run" for t in texts]
                lines.append(f"| {n:,} | {budget:.0e} | " + " | ".join(shown) + " |")
    return lines


def bbob_variants(default: list[Row], variants: dict[str, list[Row]]) -> list[str]:
    """``minimize`` on bbob-largescale with its default rule (``default``) and with each variant
    tried (``variants``, by label), where all ran."""
    b = {(int(r["n"]), int(r["function"])): r for r in default if r["method"] == "minimize"}
    a = {
        label: {(int(r["n"]), int(r["function"])): r for r in rows if r["method"] == "minimize"}
        for label, rows in variants.items()
    }
    keys = sorted(k for k in b if any(k in v for v in a.values()))
    if not keys:
        return ["(no runs of the variants on bbob-largescale)"]
    lines = [
        "| n | f | default: best - f_opt (targets; evaluations) | "
        + " | ".join(f"tried: {label}" for label in a)
        + " |",
        "|---|---|---|" + "---|" * len(a),
    ]

    def cell(r: Row) -> str:
        cap = ", capped" if r["capped"] == "1" else ""
        return f"{fmt(max(float(r['best_minus_opt']), 0.0))} ({r['targets_reached']}; {int(r['evaluations']):,}{cap})"

    for k in keys:
        cells = [cell(b[k])] + [cell(v[k]) if k in v else "not run" for v in a.values()]
        lines.append(f"| {k[0]} | f{k[1]} | " + " | ".join(cells) + " |")

    def score(t: dict[tuple[int, int], Row]) -> str:
        if not all(k in t for k in keys):
            return "-"
        return f"{sum(int(t[k]['targets_reached']) for k in keys) / (11 * len(keys)):.3f}"

    lines.append(f"| all | {len(keys)} | " + " | ".join(score(t) for t in [b, *a.values()]) + " |")
    return lines


def seeds_table(rows: list[Row]) -> list[str]:
    """``minimize`` with each step-size rule over seeds on one bbob-largescale problem
    (``seeds.py``): best - f_opt at 30,000 evaluations and at the end (targets
    reached at the end), one cell per seed."""
    by_seed: dict[tuple[str, str, str, str], dict[str, tuple[str, str]]] = defaultdict(dict)
    for r in rows:
        key = (r["label"], r["f"], r["n"], r["instance"])
        ev = int(r["evaluations"])
        early, end = by_seed[key].get(r["seed"], ("-", "-"))
        if ev == 30_000:
            early = fmt(max(float(r["best_minus_opt"]), 0.0))
        end = f"{fmt(max(float(r['best_minus_opt']), 0.0))} ({r['targets']}; {ev:,})"
        by_seed[key][r["seed"]] = (early, end)
    seeds = sorted({r["seed"] for r in rows}, key=int)
    lines = [
        "| f | n | step-size rule | " + " | ".join(f"seed {s}: at 30,000 / at the end (targets; evaluations)" for s in seeds) + " |",
        "|---|---|---|" + "---|" * len(seeds),
    ]
    for (label, f, n, _inst), cells in sorted(by_seed.items(), key=lambda kv: (int(kv[0][1]), int(kv[0][2]), kv[0][0])):
        shown = [" / ".join(cells[s]) if s in cells else "not run" for s in seeds]
        lines.append(f"| f{f} | {n} | {SEED_LABELS.get(label, label)} | " + " | ".join(shown) + " |")
    return lines


SEED_LABELS = {
    "csa": "CSA alone, no warm-up",
    "tpa": "two-point step-size adaptation",
    "guard": "TPA only where CSA agrees",
    "warm": "TPA warm-up, then CSA, no step back",
    "start": "TPA warm-up, back to the start if it beat nothing, then CSA; the full metric's rates",
    "nocov": "warm-up; the two points out of the covariance update",
    "rates": "warm-up; the two points out of the covariance update; sep-CMA-ES's rates",
    "wrates": "warm-up; sep-CMA-ES's rates",
    "fast": "the default with the warm-up twice as fast (TPA's damping halved while it lasts)",
    "rates-start": "the default with the two points out of the covariance update and sep-CMA-ES's rates",
    "tpa-rates": "TPA and sep-CMA-ES's rates",
    "nopair": "the warm-up without the two points after it",
    "default": "TPA warm-up, back to the start if it beat nothing, then CSA; sep-CMA-ES's rates (default)",
}


def overhead(rows: list[Row]) -> list[str]:
    if not rows:
        return ["(not measured)"]
    r = rows[-1]
    own, draw = float(r["minimize_seconds"]), float(r["normal_draw_seconds"])
    return [
        f"At n = {int(r['n']):,}, over {int(r['evaluations']):,} evaluations of a cheap objective, "
        f"`minimize`'s own asks and tells (drawing, the Python boundary, the update) took "
        f"**{own:.2e} s per evaluation**; numpy drawing one standard normal vector of the same "
        f"length took {draw:.2e} s, so the overhead is {own / draw:.1f} times the cost of drawing "
        "the sample."
    ]


BBOB_METHODS = {
    "minimize": "`minimize` (default)",
    "minimize-box": "`minimize` (the box [-5, 5])",
    "minimize-full": "`minimize` (`metric='full'`)",
    "sepcma": "sep-CMA-ES (pycma)",
    **PEERS,
}
# The functions every method runs at each n (``scripts/large-scale``), and pypop7's subset.
BBOB_SEVEN = [2, 1, 10, 8, 12, 7, 15]
BBOB_GRID = {n: list(range(1, 25)) for n in (20, 40, 80, 160)} | {320: BBOB_SEVEN, 640: BBOB_SEVEN}
PEERS_BBOB_GRID = {n: BBOB_SEVEN for n in (80, 160, 320, 640)}
# `metric='full'` where the default's metric is the decoded one.
FULL_BBOB_GRID = {n: list(range(1, 25)) for n in (20, 40, 80, 160)}


def bbob_score(runs: dict[tuple[int, int], dict[str, Row]], keys: list[tuple[int, int]], m: str) -> str:
    if not keys or not all(m in runs[k] for k in keys):
        return "-"
    return f"{sum(int(runs[k][m]['targets_reached']) for k in keys) / (11 * len(keys)):.3f}"


def bbob_tables(rows: list[Row]) -> list[str]:
    """The fraction of the targets each method reached per n (over the functions that
    ``minimize`` and pycma's sep-CMA-ES ran; then over pypop7's subset where it ran), and
    the runs one by one."""
    if not rows:
        return ["bbob-largescale did not run."]
    dims = sorted({int(r["n"]) for r in rows})
    methods = [m for m in BBOB_METHODS if any(r["method"] == m for r in rows)]
    runs: dict[tuple[int, int], dict[str, Row]] = defaultdict(dict)
    for r in rows:
        runs[(int(r["n"]), int(r["function"]))][r["method"]] = r
    lines = [
        "| n | functions | " + " | ".join(BBOB_METHODS[m] for m in methods) + " |",
        "|---|---|" + "---|" * len(methods),
    ]
    for n in dims:
        main = sorted(k for k in runs if k[0] == n and {"minimize", "sepcma"} <= set(runs[k]))
        lines.append(f"| {n} | {len(main)} | " + " | ".join(bbob_score(runs, main, m) for m in methods) + " |")
        peers = sorted(k for k in main if all(p in runs[k] for p in PEERS))
        if peers and len(peers) < len(main):
            fs = ", ".join(f"f{k[1]}" for k in peers)
            lines.append(f"| {n} | {fs} | " + " | ".join(bbob_score(runs, peers, m) for m in methods) + " |")
    lines += ["", "Per function (best value minus f_opt at the end; targets reached of 11):", ""]
    lines.append("| n | f | " + " | ".join(BBOB_METHODS[m] for m in methods) + " |")
    lines.append("|---|---|" + "---|" * len(methods))
    for k in sorted(runs):
        cells = [
            f"{fmt(max(float(runs[k][m]['best_minus_opt']), 0.0))} ({runs[k][m]['targets_reached']})"
            if m in runs[k] else "-"
            for m in methods
        ]  # fmt: skip
        lines.append(f"| {k[0]} | f{k[1]} | " + " | ".join(cells) + " |")
    capped = [r for r in rows if r["capped"] == "1"]
    if capped:
        lines.append("")
        lines.append("Runs stopped by the wall-time cap: " + ", ".join(f"{r['method']} f{r['function']} n={r['n']}" for r in capped))
    return lines


def bbob_missing(rows: list[Row]) -> list[str]:
    """The bbob-largescale runs of ``scripts/large-scale``'s grid that are not in ``rows``."""
    have = {(r["method"], int(r["n"]), int(r["function"])) for r in rows}
    out = []
    for method in BBOB_METHODS:
        grid = FULL_BBOB_GRID if method == "minimize-full" else (
            PEERS_BBOB_GRID if method in PEERS else BBOB_GRID)
        for n, functions in grid.items():
            lost = [f for f in functions if (method, n, f) not in have]
            if lost:
                out.append(f"bbob-largescale, {BBOB_METHODS[method]}, n = {n}: f" + ", f".join(map(str, lost)))
    return out


def as_minimize(rows: list[Row], arm: str, key: str = "arm") -> list[Row]:
    """The runs of ``arm`` (an option of ``minimize``) as the variant tables take them; ``key``
    is the column naming the arm (``method`` in the bbob csv files)."""
    return [{**r, key: "minimize"} for r in rows if r[key] == arm]


def main() -> None:
    if len(sys.argv) != 4:
        sys.exit("usage: python -m studies large-scale-page OUT PAGE COMMAND")
    out, page, command = sys.argv[1], sys.argv[2], sys.argv[3]
    rows = read(sorted(glob.glob(os.path.join(out, "texture-*.csv"))))
    bbob = read(sorted(glob.glob(os.path.join(out, "bbob*.csv"))))
    png = os.path.splitext(page)[0] + ".png"
    plot(rows, png)
    table, missing = texture_table(rows, list(ARMS), SIZES)
    yardsticks, missing_peers = texture_table(rows, YARDSTICK_ARMS, SIZES)
    boxed, missing_boxed = texture_table(rows, BOXED_ARMS, SIZES)
    missing += [m for m in missing_peers + missing_boxed if m not in missing]
    template = open(os.path.join(os.path.dirname(__file__), "page.md")).read()
    tried = {
        "TPA warm-up, then CSA, no step back": read(glob.glob(os.path.join(out, "tried-warm-texture*.csv"))),
        "CSA alone, no warm-up": read(glob.glob(os.path.join(out, "tried-csa-texture*.csv"))),
        "median success rule": read(glob.glob(os.path.join(out, "tried-msr-texture*.csv"))),
        "median success rule and sep-CMA-ES's rates": read(glob.glob(os.path.join(out, "tried-msr-rates-texture*.csv"))),
        "two-point step-size adaptation (TPA)": read(glob.glob(os.path.join(out, "tried-tpa-texture*.csv"))),
        "TPA only where CSA agrees": read(glob.glob(os.path.join(out, "tried-tpaguard-texture*.csv"))),
        "the warm-up without the two points after it": read(glob.glob(os.path.join(out, "tried-nopair-texture*.csv"))),
        "the warm-up twice as fast": read(glob.glob(os.path.join(out, "tried-fast-texture*.csv"))),
        "the low-rank-plus-diagonal metric (`metric='low_rank'`)": as_minimize(rows, "minimize-lowrank"),
    }
    tried = {k: v for k, v in tried.items() if v}
    tried_bbob = {
        "TPA warm-up, then CSA, no step back": read(sorted(glob.glob(os.path.join(out, "tried-warm-bbob*.csv")))),
        "CSA alone, no warm-up": read(sorted(glob.glob(os.path.join(out, "tried-csa-bbob*.csv")))),
        "median success rule": read(sorted(glob.glob(os.path.join(out, "tried-msr-bbob*.csv")))),
        "TPA": read(sorted(glob.glob(os.path.join(out, "tried-tpa-bbob*.csv")))),
        "the warm-up without the two points after it": read(sorted(glob.glob(os.path.join(out, "tried-nopair-bbob*.csv")))),
        "the low-rank-plus-diagonal metric (`metric='low_rank'`)": as_minimize(bbob, "minimize-lowrank", "method"),
    }
    tried_bbob = {k: v for k, v in tried_bbob.items() if v}
    seeds_path = os.path.join(out, "tried-seeds-bbob.csv")
    seeds = read([p for p in (seeds_path, os.path.join(out, "seeds-bbob.csv")) if os.path.exists(p)])
    overhead_path = os.path.join(out, "overhead.csv")
    text = template.format(
        command=command,
        time_scales="\n".join(time_scales()),
        tried="\n".join(tried_table(rows, tried)) if tried else "(no variant ran)",
        bbob_tried="\n".join(bbob_variants(bbob, tried_bbob)),
        bbob_seeds="\n".join(seeds_table(seeds)) if seeds else "(not run)",
        overhead="\n".join(overhead(read([overhead_path]) if os.path.exists(overhead_path) else [])),
        table="\n".join(table),
        yardsticks="\n".join(yardsticks),
        boxed="\n".join(boxed),
        boxed_standing=standing(rows, "minimize-box", list(BOXED)),
        plot=os.path.basename(png),
        never_worse="\n".join(never_worse(rows)),
        seconds="\n".join(seconds_per_evaluation(rows)),
        bbob="\n".join(bbob_tables(bbob)),
        missing="\n".join(f"- {m}" for m in missing + bbob_missing(bbob)) or "- nothing: every run of the grid ran",
    )
    _page.write(page, text, runs=out)


if __name__ == "__main__":
    main()
