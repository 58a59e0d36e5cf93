"""Files of the Mitsuba SHADOW example (optimize.py): the paper's figures it compares
with, where the repository is, and the writers of its images, tables and plots."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
PAPER_PARAM_MSE = 1.81e-3  # main paper Table 2, SHADOW, plateau-free gradient
PAPER_MITSUBA_PARAM_MSE = 5.06  # main paper Table 2, SHADOW, Mitsuba 3


def write_png(mi, image, path: Path) -> None:
    import numpy as np

    bmp = mi.Bitmap(np.ascontiguousarray(image, dtype=np.float32))
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True).write(str(path))


def write_csv(path: Path, rows: list[dict]) -> None:
    if not rows:
        return
    keys = list(rows[0].keys())
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else (f"{r[k]:.6e}" if isinstance(r[k], float) else r[k]))
                        for k in keys})


def read_csv(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def plot_convergence(path: Path, runs: list[tuple[str, list[dict], dict]], title: str,
                     x: str = "iteration", samples: int = 2) -> bool:
    """runs: (label, rows with iteration/param_mse/loss, matplotlib kwargs). x: "iteration", or
    "renders" (the rows' renders column; rows without one, the paper loop's, count
    samples renders an iteration)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("note: matplotlib missing, no plot (scripts/install-mitsuba installs it)", file=sys.stderr)
        return False
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    for label, rows, kw in runs:
        if x == "renders":
            it = [int(r["renders"]) if r.get("renders") else (int(r["iteration"]) + 1) * samples for r in rows]
        else:
            it = [int(r["iteration"]) for r in rows]
        a.semilogy(it, [float(r["param_mse"]) for r in rows], label=label, **kw)
        b.semilogy(it, [max(float(r["loss"]), 1e-12) for r in rows], label=label, **kw)
    a.axhline(PAPER_PARAM_MSE, color="k", ls=":", lw=1, label="paper (plateau-free) 1.81e-3")
    a.set_xlabel(x)
    a.set_ylabel("parameter MSE")
    b.set_xlabel(x)
    b.set_ylabel("image MSE (loss of the iteration's renders)")
    a.legend(fontsize=7)
    b.legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return True


def fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, (int, float)):
        return f"{v:.2e}" if (v != 0 and (abs(v) < 1e-2 or abs(v) >= 1e3)) else f"{v:.3g}"
    return str(v)
