"""The SHADOW task of docs/tasks.md as a Mitsuba 3 scene (CPU variant ``llvm_ad_rgb``).

The scene comes from ``pathtracer export shadow`` (_export.py turns the description
into Mitsuba's), so examples/pathtracer/src/tasks/shadow.rs is its only definition; the
binary is target/release/pathtracer (``cargo build --release -p pathtracer``) or
``$PATHTRACER``. It is the scene of SPEC section 2:

* pinhole camera at (17.658, 0, 0) looking along -x, +z up, horizontal field of view
  39.597755 degrees, 256x192 pixels (image right = view direction x up = +y);
* a diffuse grey (0.7) rectangle x = 0 spanning y, z in [-6.58, 6.58], facing the camera;
* a diffuse sphere of radius 0.5 at (13.57, 8.05, -2.0) + (0, theta_0, theta_1),
  reflectance (0.8, 0.262, 0.0415), outside the view: only its shadow is seen;
* a point light at (25.975, 13.776, 0) of intensity 1715;
* a constant environment of radiance (0.6, 0.6, 0.99);
* paths up to depth 6 (Mitsuba's ``max_depth``, as in our renderer).

The constants below name the task's numbers for the summaries and pages; the scene is checked
against them when it is built. Parameters theta = (y offset, z offset) in world units, unbounded, as in our task
(docs/tasks.md: "none (world units)"). Start (-0.5, 2.5), target (-1.5, 1.0).
The loss is the mean squared error over all pixels and channels of the linear images.

Importing this module needs mitsuba; ``load_mitsuba()`` gives a one-line hint without it.
"""

from __future__ import annotations

import glob
import os
import sys

START = (-0.5, 2.5)
TARGET = (-1.5, 1.0)
SPHERE_RADIUS = 0.5
WIDTH, HEIGHT = 256, 192
FOV_DEGREES = 39.597755
MAX_DEPTH = 6

INSTALL_HINT = (
    "mitsuba is not installed: run `scripts/install-mitsuba` (it installs the pinned pip package "
    "mitsuba into target/venv, and Debian's libLLVM if missing), then use target/venv/bin/python"
)


def _find_libllvm() -> str | None:
    """The newest libLLVM of version 16 or later (drjit 1.5's LLVM backend cannot use 15)."""
    import re

    found = []
    for d in ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu"):
        for p in glob.glob(d + "/libLLVM*.so*"):
            m = re.search(r"libLLVM(?:-|\.so\.)(\d+)", os.path.basename(p))
            if m and int(m.group(1)) >= 16:
                found.append((int(m.group(1)), p))
    return max(found)[1] if found else None


def load_mitsuba(variant: str = "llvm_ad_rgb"):
    """Imports mitsuba and sets ``variant``; exits with the install hint if it is missing.

    Points drjit at the newest libLLVM >= 16 (DRJIT_LIBLLVM_PATH) unless that is set.
    """
    if not os.environ.get("DRJIT_LIBLLVM_PATH"):
        lib = _find_libllvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
    try:
        import mitsuba as mi
    except ImportError:
        sys.exit(INSTALL_HINT)
    mi.set_variant(variant)
    return mi


def export_shadow(which_or_theta, scale: float = 1.0, spp: int = 32) -> dict:
    """SHADOW's description from ``pathtracer export shadow`` (the task's one definition, in
    examples/pathtracer/src/tasks/shadow.rs) at "start", "target" or the parameters given."""
    import subprocess
    import tempfile

    from studies.mitsuba import _export as mx

    with tempfile.TemporaryDirectory() as tmp:
        if isinstance(which_or_theta, str):
            return mx.run_export("shadow", tmp, which_or_theta, spp=spp, scale=scale)
        params = ",".join(repr(float(t)) for t in which_or_theta)
        subprocess.run([mx.pathtracer_binary(), "export", "shadow", f"--params={params}", "--spp", str(spp),
                        "--scale", repr(float(scale)), "--out", tmp], check=True, stdout=subprocess.DEVNULL)
        return mx.read_description(tmp)


def _check_constants(desc: dict, scale: float) -> None:
    """The constants this module names (for summaries and pages) must be the exported scene's."""
    width, height = max(1, round(WIDTH * scale)), max(1, round(HEIGHT * scale))
    sphere = desc["shapes"][0]
    problems = []
    if (desc["film"]["width"], desc["film"]["height"]) != (width, height):
        problems.append(f"film {desc['film']} != {width}x{height}")
    if abs(desc["camera"]["hfov_degrees"] - FOV_DEGREES) > 1e-4:
        problems.append(f"fov {desc['camera']['hfov_degrees']} != {FOV_DEGREES}")
    if desc["max_depth"] != MAX_DEPTH:
        problems.append(f"max_depth {desc['max_depth']} != {MAX_DEPTH}")
    if sphere["type"] != "sphere" or abs(sphere["radius"] - SPHERE_RADIUS) > 1e-6:
        problems.append(f"first shape {sphere} is not the sphere of radius {SPHERE_RADIUS}")
    if [round(t, 9) for t in desc.get("theta", [])] != list(START):
        problems.append(f"start {desc.get('theta')} != {START}")
    if problems:
        raise RuntimeError("_scene.py and `pathtracer export shadow` disagree: " + "; ".join(problems))


def scene_dict(mi, theta=START, spp: int = 32, scale: float = 1.0, integrator: dict | None = None):
    """The scene as Mitsuba reads it, from ``pathtracer export shadow`` (_export.py)
    at ``theta``; ``scale`` multiplies the resolution (the test's short run)."""
    from studies.mitsuba import _export as mx

    at_start = tuple(float(t) for t in theta) == START
    desc = export_shadow("start" if at_start else theta, scale, spp)
    if at_start:
        _check_constants(desc, scale)
    return mx.scene_dict(mi, desc, spp, integrator)


def sphere_base() -> tuple[float, float, float]:
    """The sphere's centre at theta = (0, 0), from the export (Mitsuba's AD moves it by
    (0, theta0, theta1) from there, as the task does: docs/tasks.md, SHADOW)."""
    c = export_shadow((0.0, 0.0))["shapes"][0]["center"]
    return (float(c[0]), float(c[1]), float(c[2]))


class ShadowScene:
    """The loaded scene: ``render(theta, seed)`` -> linear RGB image as a numpy array.

    Built from ``pathtracer export shadow --initial``; ``set_theta`` asks the exporter where
    the sphere is at theta (a few milliseconds beside a render), so that the Rust task is the
    only definition of how the parameters move the scene."""

    def __init__(self, mi, spp: int = 32, scale: float = 1.0, integrator: dict | None = None):
        self.mi = mi
        self.spp = spp
        self.scale = scale
        self.scene = mi.load_dict(scene_dict(mi, START, spp, scale, integrator))
        self.params = mi.traverse(self.scene)
        self.key = self._center_key()
        self._centers: dict[tuple[float, ...], list[float]] = {}

    def _center_key(self) -> str:
        for k in self.params.keys():
            if k.startswith("shape_0000_sphere.") and k.endswith("center"):
                return k
        for k in self.params.keys():
            if k.startswith("shape_0000_sphere.") and k.endswith("to_world"):
                return k
        raise KeyError(f"no sphere position among {list(self.params.keys())}")

    def center(self, theta) -> list[float]:
        """The sphere's centre at ``theta``, from the exporter (cached)."""
        key = tuple(float(t) for t in theta)
        if key not in self._centers:
            desc = export_shadow(key, self.scale, self.spp)
            self._centers[key] = [float(c) for c in desc["shapes"][0]["center"]]
        return self._centers[key]

    def set_theta(self, theta) -> None:
        mi = self.mi
        c = self.center(theta)
        if self.key.endswith("center"):
            self.params[self.key] = mi.Point3f(*c)
        else:
            self.params[self.key] = mi.Transform4f().translate(c).scale(SPHERE_RADIUS)
        self.params.update()

    def render(self, theta, seed: int = 0):
        import numpy as np

        self.set_theta(theta)
        img = self.mi.render(self.scene, seed=int(seed) & 0xFFFFFFFF, spp=self.spp)
        return np.array(img, dtype=np.float32)


def image_mse(a, b) -> float:
    import numpy as np

    return float(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2))


def param_mse(theta, target=TARGET) -> float:
    return sum((float(a) - float(b)) ** 2 for a, b in zip(theta, target)) / len(target)
