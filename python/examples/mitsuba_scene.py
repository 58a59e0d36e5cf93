"""The SHADOW task of docs/tasks.md as a Mitsuba 3 scene (CPU variant ``llvm_ad_rgb``).

Exactly the scene of SPEC section 2 and examples/pathtracer/src/tasks/shadow.rs:

* pinhole camera at (17.658, 0, 0) looking along -x, +z up, horizontal field of view
  39.597755 degrees, 256x192 pixels (image right = view direction x up = +y);
* a diffuse grey (0.7) rectangle x = 0 spanning y, z in [-6.58, 6.58], facing the camera;
* a diffuse sphere of radius 0.5 at (13.57, 8.05, -2.0) + (0, theta_0, theta_1),
  reflectance (0.8, 0.262, 0.0415), outside the view: only its shadow is seen;
* a point light at (25.975, 13.776, 0) of intensity 1715;
* a constant environment of radiance (0.6, 0.6, 0.99);
* paths up to depth 6 (Mitsuba's ``max_depth``, as in our renderer).

Parameters theta = (y offset, z offset) in world units, unbounded, as in our task
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
SPHERE_BASE = (13.57, 8.05, -2.0)
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


def scene_dict(mi, theta=START, spp: int = 32, scale: float = 1.0, integrator: dict | None = None):
    """The scene description; ``scale`` multiplies the resolution (the test's short run)."""
    T = mi.ScalarTransform4f
    width, height = max(1, round(WIDTH * scale)), max(1, round(HEIGHT * scale))
    center = [SPHERE_BASE[0], SPHERE_BASE[1] + theta[0], SPHERE_BASE[2] + theta[1]]
    return {
        "type": "scene",
        "integrator": integrator or {"type": "path", "max_depth": MAX_DEPTH},
        "sensor": {
            "type": "perspective",
            "fov": FOV_DEGREES,
            "fov_axis": "x",
            "to_world": T().look_at(origin=[17.658, 0, 0], target=[0, 0, 0], up=[0, 0, 1]),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
        # Local z (the normal) -> +x, local x -> +y, local y -> +z; 13.16 wide.
        "wall": {
            "type": "rectangle",
            "to_world": T().look_at(origin=[0, 0, 0], target=[1, 0, 0], up=[0, 0, 1]).scale([6.58, 6.58, 1]),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.7, 0.7]}},
        },
        "sphere": {
            "type": "sphere",
            "center": center,
            "radius": SPHERE_RADIUS,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.262, 0.0415]}},
        },
        "light": {
            "type": "point",
            "position": [25.975, 13.776, 0.0],
            "intensity": {"type": "rgb", "value": [1715.0, 1715.0, 1715.0]},
        },
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": [0.6, 0.6, 0.99]}},
    }


class ShadowScene:
    """The loaded scene: ``render(theta, seed)`` -> linear RGB image as a numpy array."""

    def __init__(self, mi, spp: int = 32, scale: float = 1.0, integrator: dict | None = None):
        self.mi = mi
        self.spp = spp
        self.scene = mi.load_dict(scene_dict(mi, START, spp, scale, integrator))
        self.params = mi.traverse(self.scene)
        self.key = self._center_key()

    def _center_key(self) -> str:
        for k in self.params.keys():
            if k.startswith("sphere.") and k.endswith("center"):
                return k
        for k in self.params.keys():
            if k.startswith("sphere.") and k.endswith("to_world"):
                return k
        raise KeyError(f"no sphere position among {list(self.params.keys())}")

    def set_theta(self, theta) -> None:
        mi = self.mi
        c = [SPHERE_BASE[0], SPHERE_BASE[1] + float(theta[0]), SPHERE_BASE[2] + float(theta[1])]
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
