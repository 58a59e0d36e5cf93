"""Our path tracer's binary as the renderer studies run it: the seven tasks, and one
``pathtracer render`` with the lines it reports (``render_seconds``, ``render_cpu_seconds``,
``paths``, ``rays``)."""

from __future__ import annotations

import subprocess

TASKS = ("cup", "shadow", "occlusion", "gi", "sort", "caustic", "texture")


def render_report(binary: str, task: str, repeat: int, threads: int, out: str) -> dict[str, str]:
    """``binary render TASK --target --repeat REPEAT --threads THREADS --out OUT``: the
    ``key: value`` lines it prints (the render's seconds are the median of its repeats)."""
    cmd = [binary, "render", task, "--target", "--repeat", str(repeat), "--threads", str(threads),
           "--out", out]
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return dict((k, v.strip()) for k, v in (line.split(":", 1) for line in text.splitlines()
                                            if ":" in line))
