"""Writes docs/results/image-method.md from the runs of scripts/image-method.

Usage: python3 -m studies image-method-page RUNS PAGE COMMAND
Every number on the page is read from the runs' summary.json and history.csv.
"""

import csv
import json
import sys
from pathlib import Path

from studies import _page

THRESHOLD = 1e-3


def renders_to_reach(run: Path, summary: dict) -> str:
    """The renders after which the parameter MSE first is <= THRESHOLD ("never" if not).

    The image method's rows count renders in `iteration`; the paper loop's rows are
    iterations of N renders each.
    """
    with open(run / "history.csv") as f:
        for row in csv.DictReader(f):
            if float(row["param_mse"]) <= THRESHOLD:
                k = int(row["iteration"])
                if summary["method"] != "image":
                    k = (k + 1) * summary["samples"]
                return f"{k:,}"
    return "never"


def main() -> None:
    if len(sys.argv) != 4:
        sys.exit("usage: python -m studies image-method-page RUNS PAGE COMMAND")
    runs, page, command = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3]
    rows = []
    for run in sorted(runs.iterdir()):
        path = run / "summary.json"
        if not path.is_file():
            continue
        s = json.loads(path.read_text())
        rows.append(
            "| {task} | {method} | {seed} | {N} | {renders:,} | {p0:.3e} | {p:.3e} | {img:.3e} | {reach} | {secs:.0f} |".format(
                task=s["task"].upper(),
                method=s["method"],
                seed=s["seed"],
                N=s["samples"],
                renders=s["evaluations"],
                p0=s["initial_param_mse"],
                p=s["param_mse"],
                img=s["image_mse"],
                reach=renders_to_reach(run, s),
                secs=s["seconds_total"],
            )
        )
    head = Path(__file__).with_name("page.md").read_text()
    table = "\n".join(
        [
            "| task | method | seed | N | renders | param MSE start | param MSE end | image MSE end | renders to param MSE <= 1e-3 | seconds |",
            "|---|---|---|---|---|---|---|---|---|---|",
            *rows,
        ]
    )
    _page.write(page, head.replace("{command}", command).replace("{table}", table), runs=runs)


if __name__ == "__main__":
    main()
