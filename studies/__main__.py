"""``python -m studies``: the list of studies; ``python -m studies NAME ARGS``: run one.

Run from the repository's root (``studies`` is a folder of it, not an installed package), with
the interpreter that has what the study needs (most: ``target/venv``, made by
``scripts/test-all`` or ``scripts/venv``; Mitsuba's: ``scripts/install-mitsuba``).
"""

from __future__ import annotations

import argparse
import runpy
import sys

# name: (module, what it does). A study's module runs as ``__main__`` with ARGS as its
# arguments, so ``python -m studies NAME --help`` shows its options (``run``).
STUDIES: dict[str, tuple[str, str]] = {
    "mitsuba-optimize": ("studies.mitsuba.optimize",
                         "any task on Mitsuba 3 with the Python package; SHADOW against Mitsuba's "
                         "own gradient (docs/results/mitsuba.md, mitsuba-adaptive.md, mitsuba-polished.md)"),
    "mitsuba-twins": ("studies.mitsuba.twins",
                      "every task's default method on its Mitsuba twin (docs/results/mitsuba-twins.md)"),
    "mitsuba-gradient": ("studies.mitsuba.gradient",
                         "Mitsuba's own gradient on every task (docs/results/mitsuba-gradient.md)"),
    "mitsuba-agreement": ("studies.mitsuba.agreement",
                          "our renderer's images against Mitsuba's (docs/results/mitsuba-agreement.md)"),
    "mitsuba-mixed": ("studies.mitsuba.mixed",
                      "plateau-free's gradient and Mitsuba's in one backward pass (docs/results/mitsuba-mixed.md)"),
    "mitsuba-tasks": ("studies.mitsuba.tasks_page",
                      "every task on both renderers beside the paper (docs/results/mitsuba-tasks.md)"),
    "render-speed": ("studies.renderer.speed",
                     "our renderer's time per render against Mitsuba's (docs/results/render-speed.md)"),
    "render-ab": ("studies.renderer.ab",
                  "two pathtracer binaries' CPU seconds per render, task by task, interleaved"),
    "same-images": ("studies.renderer.same_images",
                    "whether two pathtracer binaries draw the same images, bit for bit"),
    "large-scale": ("studies.large_scale.run",
                    "the texture task and bbob-largescale runs (scripts/large-scale runs them all)"),
    "large-scale-page": ("studies.large_scale.page",
                         "docs/results/large-scale.md from the runs of large-scale"),
    "large-scale-seeds": ("studies.large_scale.seeds",
                          "minimize on bbob-largescale over seeds, at many evaluation counts"),
    "stopping-bbob": ("studies.stopping.bbob",
                      "minimize's stop rules on bbob: targets reached against evaluations spent "
                      "(docs/results/stopping-bbob.md)"),
    "coco": ("studies.coco.main",
             "minimize and its peers on COCO's bbob and bbob-mixint suites (docs/results/coco.md)"),
    "peers": ("studies.peers.peers",
              "pycma's BIPOP-CMA-ES and nevergrad's NGOpt on examples/compare's instances "
              "(scripts/compare-peers)"),
    "nevergrad": ("studies.peers.nevergrad",
                  "the library's optimisers against nevergrad's on its functions (docs/results/nevergrad.md)"),
    "image-method-page": ("studies.image_method.page",
                          "docs/results/image-method.md from the runs of scripts/image-method"),
    "overhead": ("studies.overhead.binding",
                 "the Python binding's cost per evaluation (docs/python.md)"),
    "adapters": ("studies.overhead.adapters",
                 "the JAX, PyTorch and scipy adapters' cost (docs/integrations.md)"),
    "drjit-overhead": ("studies.overhead.drjit",
                       "plateau_free.drjit.PlateauFreeOp's cost per backward pass (docs/integrations.md)"),
    "ray-scaling": ("studies.overhead.ray_scaling",
                    "RayEvaluator's speed-up against its workers (docs/results/ray-scaling.md)"),
    "mpi-scaling": ("studies.overhead.mpi_scaling",
                    "plateau-free-mpi's speed-up and overhead (docs/results/mpi-scaling.md)"),
}


def listing() -> str:
    """The studies, one a line, with what each does."""
    width = max(map(len, STUDIES))
    lines = ["python -m studies NAME [ARGS]   (NAME --help for a study's options)", ""]
    lines += [f"  {name:<{width}}  {what}" for name, (_, what) in STUDIES.items()]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help", "list"):
        print(listing())
        return 0
    name, rest = argv[0], argv[1:]
    if name not in STUDIES:
        print(f"unknown study {name!r}\n\n{listing()}", file=sys.stderr)
        return 2
    run(STUDIES[name][0], f"python -m studies {name}", rest)
    return 0


def run(module: str, prog: str, args: list[str]) -> None:
    """Run ``module`` as ``__main__`` with ``args``, its argument parsers named ``prog``.

    runpy puts the module's file in ``sys.argv[0]``, which argparse would show as the program
    (``usage: optimize.py``); a study's parsers are made while it runs, so for that time a
    parser given no name takes ``prog``, the command that runs the study.
    """
    init = argparse.ArgumentParser.__init__

    def named(self: argparse.ArgumentParser, *a: object, **k: object) -> None:
        if not a:  # the first positional argument is prog
            k.setdefault("prog", prog)
        init(self, *a, **k)

    sys.argv = [prog, *args]
    argparse.ArgumentParser.__init__ = named  # type: ignore[method-assign]
    try:
        runpy.run_module(module, run_name="__main__", alter_sys=True)
    finally:
        argparse.ArgumentParser.__init__ = init  # type: ignore[method-assign]


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
