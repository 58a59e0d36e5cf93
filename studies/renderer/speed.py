"""Our renderer's time per render against Mitsuba 3's (``llvm_ad_rgb``), side by side.

For each task, at its target parameters, resolution, spp and max depth (``pathtracer export``
gives Mitsuba the same scene, studies/mitsuba/_export.py), both renderers render in one process run,
interleaved: every repetition times our renderer (``pathtracer render TASK --target --repeat
K``, which prints the median of K back-to-back renders, scene set-up excluded), then, if
``--baseline`` names another pathtracer binary (e.g. the build before a change), that one the
same way, then Mitsuba (K renders, their median); the order of the renderers turns by one each
repetition so that neither always runs first. The table gives the medians over repetitions and
the ratios. Each renderer's turn starts after a pause (``SETTLE``): a pathtracer process started
right after a Mitsuba render (2 of every 3 repetitions for the first renderer, 1 of 3 for the
second) ran TEXTURE's 2.4 ms render in 4.6 ms, so the first column's medians were those of the
slowed runs and the second's were not (drjit's worker threads staying busy for a while after a
render are the likely cause).

Mitsuba in steady state: its first render of a task compiles the JIT kernels and is left out of
the timed renders (and reported on its own, as "first render"); drjit keeps compiled kernels in
a cache directory under ``$HOME``, so ``HOME`` is pointed at a fresh temporary directory for
this process, which makes that first render a cold compile. Between timed renders the seed
changes and one diffuse reflectance of the scene is scaled by 1 + 1e-4 through
``mi.traverse`` / ``params.update()`` (untimed), the way an optimisation changes a parameter
between renders; drjit then reuses the cached kernels, and the page reports how many timed
renders compiled anything (``dr.kernel_history``: 0 means pure steady state). A timed render is
``mi.render`` followed by ``dr.eval`` and ``dr.sync_thread`` (the image is computed, not
queued).

Both renderers use the same number of threads (``--threads``, default: all cores; ours through
``--threads``, Mitsuba's through ``dr.set_thread_count``).

    target/venv/bin/python -m studies render-speed --out docs/results/render-speed.md

Needs mitsuba (``scripts/install-mitsuba``) and the pathtracer binary (``cargo build --release
-p pathtracer``; ``$PATHTRACER`` names another).
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any


from studies.mitsuba import _export as mx
from studies import _page
from studies.renderer.binary import TASKS, render_report

GOAL = 0.5  # the goal: at most half Mitsuba's time per render
# Seconds to wait before each renderer's turn, so that none starts while the one before still
# keeps the cores busy (see the docstring).
SETTLE = 0.2


# Per task, one render's work as our binary reports it (`paths: N`, `rays: M`) and the CPU
# seconds per render of each of its runs (`render_cpu_seconds`); a binary that does not report
# them (an older build) leaves them out.
WORK: dict[str, dict[str, Any]] = {}


def ours_seconds(binary: str, task: str, threads: int, inner: int, workdir: Path) -> float:
    """Median of `inner` back-to-back renders of our renderer, as the binary reports it (and
    the render's paths and rays into `WORK[task]` when it reports them)."""
    fields = render_report(binary, task, inner, threads, str(workdir / f"{task}.exr"))
    if "render_seconds" not in fields:
        raise RuntimeError(f"{binary} render {task}: no render_seconds in its output: {fields}")
    if binary == os.environ.get("PATHTRACER") and all(
            k in fields for k in ("paths", "rays", "render_cpu_seconds")):
        work = WORK.setdefault(task, {"paths": int(fields["paths"]), "rays": int(fields["rays"]),
                                      "cpu": []})
        work["cpu"].append(float(fields["render_cpu_seconds"]))
    return float(fields["render_seconds"])


class MitsubaTask:
    """One task's scene loaded into Mitsuba, with a parameter to nudge between renders."""

    def __init__(self, mi: Any, dr: Any, task: str, workdir: Path) -> None:
        self.mi, self.dr = mi, dr
        self.desc = mx.run_export(task, workdir / task)
        self.spp = int(self.desc["spp"])
        self.scene = mi.load_dict(mx.scene_dict(mi, self.desc))
        self.params = mi.traverse(self.scene)
        keys = [k for k in self.params.keys() if k.endswith("reflectance.value")]
        self.key = keys[0] if keys else None
        self.seed = 0
        self.compiled = 0  # timed renders that compiled a kernel
        self.compile_ms = 0.0  # compile time (codegen + LLVM backend) of the last render

    def nudge(self) -> None:
        """A new seed and a slightly different reflectance, as between optimisation steps."""
        self.seed += 1
        if self.key is not None:
            self.params[self.key] = self.params[self.key] * 1.0001
            self.params.update()

    def render(self) -> float:
        """Seconds of one render (computed, not only queued)."""
        dr = self.dr
        dr.kernel_history()  # empties the history
        t = time.perf_counter()
        img = self.mi.render(self.scene, seed=self.seed, spp=self.spp)
        dr.eval(img)
        dr.sync_thread()
        seconds = time.perf_counter() - t
        # Entries without a cache_hit field are not JIT kernels (e.g. memory copies).
        misses = [k for k in dr.kernel_history() if k.get("cache_hit") == 0]
        if misses:
            self.compiled += 1
        self.compile_ms = sum(k.get("codegen_time", 0.0) + k.get("backend_time", 0.0) for k in misses)
        return seconds

    def timed(self, inner: int) -> float:
        """Median of `inner` renders, each after a nudge (the nudges untimed)."""
        times = []
        for _ in range(inner):
            self.nudge()
            times.append(self.render())
        return statistics.median(times)


def load_mitsuba(threads: int) -> tuple[Any, Any]:
    from studies.mitsuba._scene import load_mitsuba as load

    mi = load("llvm_ad_rgb")
    import drjit as dr

    dr.set_thread_count(threads)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    return mi, dr


def measure(args: argparse.Namespace, workdir: Path) -> list[dict[str, Any]]:
    mi, dr = load_mitsuba(args.threads)
    rows = []
    for task in args.tasks:
        m = MitsubaTask(mi, dr, task, workdir)
        m.seed = -1
        t = time.perf_counter()
        m.nudge()
        first = m.render()
        first_compile = m.compile_ms / 1000.0
        m.compiled = 0
        renderers: list[tuple[str, Any]] = [
            ("ours", lambda: ours_seconds(args.ours, task, args.threads, args.inner, workdir)),
        ]
        if args.baseline:
            renderers.append(
                ("baseline", lambda: ours_seconds(args.baseline, task, args.threads, args.inner, workdir)))
        renderers.append(("mitsuba", lambda: m.timed(args.inner)))
        times: dict[str, list[float]] = {name: [] for name, _ in renderers}
        for rep in range(args.repeat):
            k = rep % len(renderers)
            for name, run in renderers[k:] + renderers[:k]:
                time.sleep(SETTLE)
                times[name].append(run())
        row = {name: statistics.median(v) for name, v in times.items()}
        row.update(task=task, width=m.desc["film"]["width"], height=m.desc["film"]["height"],
                   spp=m.spp, depth=int(m.desc["max_depth"]), first=first,
                   first_compile=first_compile, compiled=m.compiled,
                   timed_renders=args.repeat * args.inner, wall=time.perf_counter() - t,
                   work=WORK.get(task))
        rows.append(row)
        print(f"{task}: " + ", ".join(f"{n} {row[n]:.4f} s" for n in times), flush=True)
    return rows


def page(args: argparse.Namespace, rows: list[dict[str, Any]], load: tuple[float, float]) -> str:
    base = bool(args.baseline)
    head = "| task | resolution | spp | depth | ours (s) |"
    rule = "|---|---|---|---|---|"
    if base:
        head += " before (s) | before / ours |"
        rule += "---|---|"
    head += " Mitsuba (s) | ours / Mitsuba |"
    rule += "---|---|"
    if base:
        head += " before / Mitsuba |"
        rule += "---|"
    head += f" goal <= {GOAL} | ours: M paths / CPU s | ours: M rays / CPU s |"
    rule += "---|---|---|"
    head += " Mitsuba first render (s) | its kernel compile (s) |"
    rule += "---|---|"
    lines = [head, rule]
    for r in rows:
        ratio = r["ours"] / r["mitsuba"]
        cells = [r["task"], f"{r['width']}x{r['height']}", str(r["spp"]), str(r["depth"]),
                 f"{r['ours']:.4f}"]
        if base:
            cells += [f"{r['baseline']:.4f}", f"{r['baseline'] / r['ours']:.2f}"]
        cells += [f"{r['mitsuba']:.4f}", f"{ratio:.2f}"]
        if base:
            cells.append(f"{r['baseline'] / r['mitsuba']:.2f}")
        cells.append("met" if ratio <= GOAL else "not met")
        cells += throughput(r)
        cells += [f"{r['first']:.2f}", f"{r['first_compile']:.2f}"]
        lines.append("| " + " | ".join(cells) + " |")
    compiled = sum(r["compiled"] for r in rows)
    timed = sum(r["timed_renders"] for r in rows)
    cmd = "target/venv/bin/python -m studies render-speed " + shlex.join(args.argv)
    cpu = _cpu_model()
    return "\n".join([
        "# Render time: our path tracer against Mitsuba 3",
        "",
        "Seconds per render at each task's target parameters, resolution, spp and max depth "
        "(the goal: ours / Mitsuba <= 0.5). Written by",
        "",
        f"    {cmd.strip()}",
        "",
        f"Mitsuba {args.mitsuba_version} (`llvm_ad_rgb`, `path` integrator). Both renderers on "
        f"{args.threads} threads ({os.cpu_count()} cores, {cpu}). Each cell is the median over "
        f"{args.repeat} interleaved repetitions, each the median of {args.inner} back-to-back "
        "renders; the order of the renderers turns every repetition, and each turn starts "
        f"after a {SETTLE} s pause (a render started right after Mitsuba's ran slower). Ours: "
        "`pathtracer render TASK --target --repeat K --threads T` (render alone, scene set-up "
        "excluded)"
        + (f"; before: the same command with `{args.baseline_label}`" if base else "")
        + ". Mitsuba in steady state: the first render (cold: a fresh kernel cache) is left "
        "out and shown in its own columns (its time, and the kernel compile time drjit reports "
        "for it: code generation + LLVM backend); between timed renders the seed changes and a "
        "diffuse reflectance is scaled by 1 + 1e-4 through `params.update()` (untimed); "
        f"{compiled} of {timed} timed Mitsuba renders compiled a kernel. A timed Mitsuba render "
        "is `mi.render` + `dr.eval` + `dr.sync_thread`.",
        "",
        f"Load average (1 min) {load[0]:.2f} at the start, {load[1]:.2f} at the end "
        f"({os.cpu_count()} cores): the machine was shared with other jobs, so absolute seconds "
        "are noisy; the ratios come from interleaved renders of one run.",
        "",
        "Throughput (ours): one render's camera paths (pixels x spp) and rays (closest-hit "
        "queries, last-segment queries and shadow rays, as `pathtracer render` counts them) "
        "per second of CPU time, in millions: per core actually busy with the render. The CPU "
        "time is the render's threads' time on a core as Linux counts it "
        "(`render_cpu_seconds`, the median over our runs), so time the cores spent on other "
        "jobs is left out; sharing a core's caches with them still slows it.",
        "",
        *lines,
        "",
    ])


def throughput(row: dict[str, Any]) -> list[str]:
    """Our millions of paths and rays per CPU second, or dashes without the counts."""
    work = row.get("work")
    if not work:
        return ["-", "-"]
    cpu = statistics.median(work["cpu"])
    return [f"{work['paths'] / cpu / 1e6:.1f}", f"{work['rays'] / cpu / 1e6:.1f}"]


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tasks", nargs="+", default=list(TASKS), choices=TASKS)
    p.add_argument("--repeat", type=int, default=7, help="interleaved repetitions (default 7)")
    p.add_argument("--inner", type=int, default=3, help="renders per repetition (default 3)")
    p.add_argument("--threads", type=int, default=os.cpu_count() or 1,
                   help="threads of both renderers (default: all cores)")
    p.add_argument("--ours", default=mx.pathtracer_binary(), help="our pathtracer binary")
    p.add_argument("--baseline", help="another pathtracer binary timed alongside (e.g. before a change)")
    p.add_argument("--baseline-label", default="the binary before the change",
                   help="how the page names --baseline")
    p.add_argument("--out", help="markdown page to write")
    args = p.parse_args(argv)
    args.argv = sys.argv[1:] if argv is None else argv
    for name in ("repeat", "inner", "threads"):
        if getattr(args, name) < 1:
            raise ValueError(f"--{name}: {getattr(args, name)}; must be at least 1")
    os.environ["PATHTRACER"] = args.ours
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        # drjit caches compiled kernels under $HOME: a fresh one makes the first render cold.
        os.environ["HOME"] = tmp
        rows = measure(args, Path(tmp))
        import mitsuba

        args.mitsuba_version = mitsuba.__version__
    text = page(args, rows, (load0, os.getloadavg()[0]))
    print(text)
    if args.out:
        _page.write(args.out, text)


if __name__ == "__main__":
    main()
