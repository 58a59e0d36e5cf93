"""Does our renderer draw what Mitsuba 3 draws? Every task, from one scene description.

For each task and each of its start and target parameters: ``pathtracer export`` writes the
scene (_export.py loads it into Mitsuba), ``pathtracer render`` renders it with our
renderer (seed 0) and Mitsuba (``llvm_ad_rgb``, ``path`` integrator, the same spp and
max_depth) renders it with seeds 0 and 1. The images are compared in 4x4-pixel block means
of linear radiance:

    error(a, b) = sum over blocks and channels |A - B| / sum |B|

(A, B the block means of a and b; the relative L1 error of the block means). ``error(ours,
Mitsuba seed 0)`` is the agreement; ``error(Mitsuba seed 1, Mitsuba seed 0)`` is the noise
floor, what two renders of the same scene by the same renderer differ by. The goal:
the agreement within 2 %.

    target/venv/bin/python -m studies mitsuba-agreement --out docs/results/mitsuba-agreement

writes ``OUT/<task>-<start|target>.png`` (ours, Mitsuba, their block difference),
``OUT/agreement.json`` and the page ``OUT.md``. Needs mitsuba (``scripts/install-mitsuba``)
and the pathtracer binary (``cargo build --release -p pathtracer``; ``$PATHTRACER`` names
another).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from studies import _page
from studies.mitsuba import _export as mx


TASKS = ("cup", "shadow", "occlusion", "gi", "sort", "caustic", "texture")
BLOCK = 4
GOAL = 0.02  # the goal: within 2 %
FLOOR_FACTOR = 1.5  # what the test allows (python/tests/test_mitsuba_agreement.py)


def block_means(img: np.ndarray, block: int = BLOCK) -> np.ndarray:
    """Means over ``block`` x ``block`` pixel blocks (a partial last row or column is dropped)."""
    h, w, c = img.shape
    h, w = h // block * block, w // block * block
    if h == 0 or w == 0:
        raise ValueError(f"image {img.shape[:2]} is smaller than one {block}x{block} block")
    return img[:h, :w].reshape(h // block, block, w // block, block, c).mean(axis=(1, 3))


def relative_error(a: np.ndarray, b: np.ndarray, block: int = BLOCK) -> float:
    """sum |A - B| / sum |B| over the ``block`` x ``block`` block means A, B of a and b."""
    if a.shape != b.shape:
        raise ValueError(f"images of different sizes: {a.shape} and {b.shape}")
    A, B = block_means(a, block), block_means(b, block)
    return float(np.abs(A - B).sum() / np.abs(B).sum())


def render_ours(task: str, which: str, spp: int, scale: float | None, seed: int, out: Path) -> np.ndarray:
    """Our renderer's linear image (``pathtracer render``, written as EXR and read back)."""
    path = out / "ours.exr"
    cmd = [mx.pathtracer_binary(), "render", task, "--initial" if which == "start" else "--target",
           "--spp", str(spp), "--seed", str(seed), "--out", str(path)]
    if scale is not None:
        cmd += ["--scale", repr(float(scale))]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    import mitsuba as mi

    return np.array(mi.Bitmap(str(path)), dtype=np.float64)


def reordered(desc_dict: dict[str, Any]) -> dict[str, Any]:
    """The Mitsuba scene dictionary with its shapes that emit nothing listed in reverse order
    (emitting shapes keep theirs, so the emitters and every random number stay the same)."""
    shapes = [k for k in desc_dict if k.startswith("shape_")]
    plain = [k for k in shapes if "emitter" not in desc_dict[k]]
    order = iter(reversed(plain))
    out = {k: v for k, v in desc_dict.items() if not k.startswith("shape_")}
    for k in shapes:
        src = k if "emitter" in desc_dict[k] else next(order)
        out[f"re{len(out):04d}_{k}"] = desc_dict[src]
    return out


def overlapping_boxes(desc: dict[str, Any]) -> int:
    """Pairs of axis-aligned boxes of different materials that overlap (their coincident
    faces are drawn in whichever colour a renderer happens to test first)."""
    boxes = []
    for s in desc["shapes"]:
        m = np.array(s["to_world"], dtype=np.float64) if s["type"] == "box" else None
        if m is not None and np.allclose(m[:, :3], np.diag(np.diag(m[:, :3]))):
            boxes.append((m[:, 3], np.abs(np.diag(m[:, :3])), s["material"]))
    return sum(
        bool(np.all(np.abs(ci - cj) < hi + hj)) and mi_ != mj
        for i, (ci, hi, mi_) in enumerate(boxes) for (cj, hj, mj) in boxes[i + 1:]
    )


def compare(mi, task: str, which: str, spp: int, scale: float | None = None,
            workdir: Path | None = None) -> dict[str, Any]:
    """One comparison: the three images, the agreement and the noise floor, and the times."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(workdir or tmp)
        out.mkdir(parents=True, exist_ok=True)
        desc = mx.run_export(task, out, which, spp=spp, scale=scale)
        t0 = time.perf_counter()
        ours = render_ours(task, which, spp, scale, 0, out)
        t1 = time.perf_counter()
        m0 = mx.render(mi, desc, seed=0)
        t2 = time.perf_counter()
        m1 = mx.render(mi, desc, seed=1)
        spp_ = int(desc["spp"])
        shuffled = mi.load_dict(reordered(mx.scene_dict(mi, desc, spp_)))
        m_order = np.array(mi.render(shuffled, seed=0, spp=spp_), dtype=np.float64)
    return {
        "task": task, "params": which, "spp": spp, "max_depth": int(desc["max_depth"]),
        "width": int(desc["film"]["width"]), "height": int(desc["film"]["height"]),
        "error": relative_error(ours, m0), "noise_floor": relative_error(m1, m0),
        "mean_ratio": float(ours.mean() / m0.mean()),
        "order_effect": relative_error(m_order, m0), "overlapping_boxes": overlapping_boxes(desc),
        "ours_seconds": t1 - t0, "mitsuba_seconds": t2 - t1,
        "images": (ours, m0, m1),
    }


def difference_image(a: np.ndarray, b: np.ndarray, full: float) -> np.ndarray:
    """The block means' difference a - b: its size is the error's, sum over the channels of
    |A - B| over the sum of B's mean block, full colour at ``full``; red where a is brighter
    (mean over the channels), blue where darker. Upsampled back to the image's size."""
    A, B = block_means(a), block_means(b)
    size = np.abs(A - B).sum(axis=2) / max(float(B.sum(axis=2).mean()), 1e-12) / full
    size = np.clip(size, 0.0, 1.0)
    brighter = (A - B).mean(axis=2) >= 0.0
    vis = np.zeros(size.shape + (3,))
    vis[..., 0] = np.where(brighter, size, 0.0)
    vis[..., 2] = np.where(brighter, 0.0, size)
    vis = np.repeat(np.repeat(vis, BLOCK, axis=0), BLOCK, axis=1)
    canvas = np.zeros_like(a)
    canvas[: vis.shape[0], : vis.shape[1]] = vis
    return canvas


def write_strip(mi, row: dict[str, Any], path: Path, full: float) -> None:
    """ours | Mitsuba | ours - Mitsuba | Mitsuba seed 1 - seed 0, side by side, as an sRGB PNG."""
    ours, mits, other = row["images"]
    gap = np.ones((ours.shape[0], 4, 3))
    strip = np.concatenate([ours, gap, mits, gap, difference_image(ours, mits, full), gap,
                            difference_image(other, mits, full)], axis=1)
    zoom = max(1, -(-256 // ours.shape[1]))  # small images enlarged (nearest) to 256 wide
    strip = np.repeat(np.repeat(strip, zoom, axis=0), zoom, axis=1)
    bmp = mi.Bitmap(np.ascontiguousarray(strip, dtype=np.float32))
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True).write(str(path))


def page(rows: list[dict[str, Any]], out: Path, args: argparse.Namespace, seconds: float) -> str:
    """The markdown page."""
    lines = [
        "# Our renderer against Mitsuba 3, every task",
        "",
        "Written by `target/venv/bin/python -m studies mitsuba-agreement "
        + " ".join(sys.argv[1:]) + "` (docs/mitsuba.md, \"Agreement\").",
        "Each task's scene is described once, in its Rust file: `pathtracer export` writes it and",
        "`studies/mitsuba/_export.py` loads the description into Mitsuba 3 (`llvm_ad_rgb`,",
        "`path` integrator); the equivalent choices Mitsuba needs are listed in",
        "[../tasks.md](../tasks.md), \"The same scenes in Mitsuba 3\".",
        "",
        f"Every image at the task's resolution{'' if args.scale is None else f' times {args.scale}'}, "
        f"{args.spp} spp, the task's depth; ours with seed 0, Mitsuba with seeds 0 and 1.",
        "**Error** = sum over 4x4-pixel blocks and channels of |ours - Mitsuba| / sum of Mitsuba's",
        "(block means of linear radiance, Mitsuba seed 0). **Noise floor** = the same error between",
        "Mitsuba's seeds 1 and 0: what the Monte Carlo noise alone gives at this spp. Two unbiased",
        "renders of one scene differ by about the noise floor (less when ours is the less noisy);",
        "a scene that drifts adds its difference on top. **Mean** = ours / Mitsuba's mean pixel.",
        "**Shape order** = the same error between Mitsuba's seed 0 and Mitsuba's seed 0 with the",
        "shapes that emit nothing listed in reverse order (the same random numbers): what the",
        "picture owes to the order a renderer tests shapes in. It is zero unless two surfaces",
        "coincide (drawn in whichever colour is tested first) or rounding sends a path elsewhere;",
        "**overlaps** = pairs of boxes of different colours that overlap (coincident faces).",
        "Goal: error within 2 %.",
        "",
        "| task | params | size | spp | depth | error | noise floor | error / floor | mean | shape order | overlaps | within 2 % |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['task']} | {r['params']} | {r['width']}x{r['height']} | {r['spp']} | {r['max_depth']} "
            f"| {100 * r['error']:.2f} % | {100 * r['noise_floor']:.2f} % | {r['error'] / r['noise_floor']:.2f} "
            f"| {r['mean_ratio']:.4f} | {100 * r['order_effect']:.2f} % | {r['overlapping_boxes']} "
            f"| {'yes' if r['error'] <= GOAL else '**no**'} |"
        )
    met = sum(r["error"] <= GOAL for r in rows)
    above = [f"{r['task']} {r['params']} ({r['error'] / r['noise_floor']:.1f} times its floor)"
             for r in rows if r["error"] > FLOOR_FACTOR * r["noise_floor"]]
    ambiguous = [f"{r['task']} {r['params']} ({100 * r['order_effect']:.2f} %, {r['overlapping_boxes']} overlaps)"
                 for r in rows if r["order_effect"] > 0.1 * r["noise_floor"]]
    lines += [
        "",
        f"Errors above {FLOOR_FACTOR} times the noise floor: {', '.join(above) or 'none'}. "
        f"Scenes whose picture depends on the shape order (by more than a tenth of the floor): "
        f"{', '.join(ambiguous) or 'none'}.",
        "",
        f"{met} of {len(rows)} comparisons within 2 %. Seconds per image (2 shared cores): ours "
        f"median {np.median([r['ours_seconds'] for r in rows]):.2f}, Mitsuba median "
        f"{np.median([r['mitsuba_seconds'] for r in rows]):.2f} (a render includes loading "
        f"the scene and compiling its kernels); the whole page {seconds / 60:.1f} minutes on "
        f"{platform.machine()} with load average {os.getloadavg()[0]:.1f} at its end.",
        "",
        f"Images: ours | Mitsuba | ours minus Mitsuba | Mitsuba's seed 1 minus its seed 0 (the "
        f"noise). A difference is drawn per 4x4 block: its brightness is the sum over the channels "
        f"of |A - B| relative to B's mean block (the error's terms), full at {100 * args.full:.0f} %; "
        f"red where the first is brighter, blue where darker. Images narrower than 256 pixels are "
        f"enlarged (nearest neighbour).",
        "",
    ]
    for r in rows:
        name = f"{r['task']}-{r['params']}.png"
        lines += [f"**{r['task']}, {r['params']}** (error {100 * r['error']:.2f} %, noise floor "
                  f"{100 * r['noise_floor']:.2f} %)", "", f"![{r['task']} {r['params']}]({out.name}/{name})", ""]
    return "\n".join(lines)


def parse(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="folder of the images; the page is OUT.md")
    p.add_argument("--tasks", default=",".join(TASKS), help="comma-separated tasks [default: all]")
    p.add_argument("--params", default="start,target", help="start, target or both [default: both]")
    p.add_argument("--spp", type=int, default=1024, help="samples per pixel of every image [default: 1024]")
    p.add_argument("--scale", type=float, default=None, help="resolution multiplier [default: 1]")
    p.add_argument("--full", type=float, default=0.1,
                   help="relative block difference shown in full colour [default: 0.1]")
    args = p.parse_args(argv)
    tasks = [t.strip().lower() for t in args.tasks.split(",") if t.strip()]
    bad = [t for t in tasks if t not in TASKS]
    if bad or not tasks:
        p.error(f"--tasks: {args.tasks!r}; allowed: {', '.join(TASKS)}")
    which = [w.strip() for w in args.params.split(",") if w.strip()]
    if not which or any(w not in ("start", "target") for w in which):
        p.error(f"--params: {args.params!r}; allowed: start, target, or both comma-separated")
    if args.spp < 1:
        p.error(f"--spp: {args.spp}; allowed: a whole number >= 1")
    if args.scale is not None and not 0 < args.scale <= 64:
        p.error(f"--scale: {args.scale}; allowed: a number > 0 and <= 64")
    if not 0 < args.full < float("inf"):
        p.error(f"--full: {args.full}; allowed: a number > 0")
    args.task_list, args.which = tasks, which
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse(argv)
    from studies.mitsuba._scene import load_mitsuba

    mi = load_mitsuba()
    binary = mx.pathtracer_binary()
    if not os.access(binary, os.X_OK):
        sys.exit(f"no pathtracer binary at {binary}: run `cargo build --release -p pathtracer` (or set PATHTRACER)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    rows = []
    for task in args.task_list:
        for which in args.which:
            row = compare(mi, task, which, args.spp, args.scale)
            write_strip(mi, row, out / f"{task}-{which}.png", args.full)
            print(f"{task} {which}: error {100 * row['error']:.2f} %, noise floor "
                  f"{100 * row['noise_floor']:.2f} %", flush=True)
            rows.append(row)
    seconds = time.perf_counter() - start
    with open(out / "agreement.json", "w") as f:
        json.dump([{k: v for k, v in r.items() if k != "images"} for r in rows], f, indent=1)
    page_path = out.parent / f"{out.name}.md"
    _page.write(page_path, page(rows, out, args, seconds), runs=out)
    print(page_path)


if __name__ == "__main__":
    main()
