"""Do two pathtracer binaries draw the same images, bit for bit? (docs/renderer.md, speed.)

Renders every task at its start and target parameters (seed 0, the task's defaults) with
binary OLD on two threads and binary NEW on one, and compares the linear EXR images value by
value (as bits: -0.0 and 0.0 differ, NaNs compare by payload). The files' bytes are not
compared: the EXR writer may order blocks differently between two writes of one image.
Exit status 1 when any value differs.

    target/venv/bin/python -m studies same-images target/pathtracer-before target/release/pathtracer

Reads EXR with mitsuba's Bitmap (``scripts/install-mitsuba``).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from studies.renderer.binary import TASKS


def render(binary: str, task: str, which: str, threads: int, out: Path) -> None:
    subprocess.run([binary, "render", task, f"--{which}", "--threads", str(threads), "--out", str(out)],
                   check=True, stdout=subprocess.DEVNULL)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("old", help="pathtracer binary rendering on two threads")
    p.add_argument("new", help="pathtracer binary rendering on one thread")
    p.add_argument("--tasks", nargs="+", default=list(TASKS), choices=TASKS)
    args = p.parse_args(argv)
    from studies.mitsuba._scene import load_mitsuba

    mi = load_mitsuba("scalar_rgb")
    differing = 0
    with tempfile.TemporaryDirectory() as tmp:
        for task in args.tasks:
            for which in ("initial", "target"):
                a, b = Path(tmp) / "old.exr", Path(tmp) / "new.exr"
                render(args.old, task, which, 2, a)
                render(args.new, task, which, 1, b)
                x = np.array(mi.Bitmap(str(a)), dtype=np.float32)
                y = np.array(mi.Bitmap(str(b)), dtype=np.float32)
                n = int((x.view(np.uint32) != y.view(np.uint32)).sum()) if x.shape == y.shape else x.size
                differing += n
                print(f"{task} {which}: " + ("identical" if n == 0 else f"{n} of {x.size} values differ"))
    print("all images identical" if differing == 0 else "images differ")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())
