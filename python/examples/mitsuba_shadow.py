"""Mitsuba 3: move a ball the camera never sees until its shadow matches a target image.

    python python/examples/mitsuba_shadow.py [BUDGET]   # needs pip install "plateau-free[mitsuba]"

The camera looks down at a floor; a point light above casts the ball's shadow on it; the ball
itself is above the camera, out of view. At the start the two shadows do not overlap, so a
small move of the ball leaves the image loss unchanged: a plateau, where Mitsuba's own
gradient is zero. `plateau_free.minimize` needs only the renders' losses. Every render uses
the same seed, so the loss is a deterministic function of the ball's position.
"""

import glob
import os
import sys

import numpy as np

import plateau_free

# drjit's CPU backend loads libLLVM (16 or later); scripts/install-mitsuba installs one.
if not os.environ.get("DRJIT_LIBLLVM_PATH"):
    found = sorted(glob.glob("/usr/lib/*-linux-gnu/libLLVM*.so.1[6-9]*"))
    if found:
        os.environ["DRJIT_LIBLLVM_PATH"] = found[-1]
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
T = mi.ScalarTransform4f
scene = mi.load_dict({
    "type": "scene",
    "integrator": {"type": "direct"},
    "sensor": {"type": "perspective", "fov": 60,
               "to_world": T().look_at(origin=[0, 0, 3], target=[0, 0, 0], up=[0, 1, 0]),
               "film": {"type": "hdrfilm", "width": 48, "height": 48, "rfilter": {"type": "box"}}},
    "floor": {"type": "rectangle", "to_world": T().scale([3, 3, 1]), "bsdf": {"type": "diffuse"}},
    "ball": {"type": "sphere", "center": [0, 0, 4], "radius": 0.3},
    "light": {"type": "point", "position": [0, 0, 8], "intensity": 60.0},
})
params = mi.traverse(scene)
key = "ball.center" if "ball.center" in params else "ball.to_world"


def render(xy):
    """The image with the ball at height 4 above the floor point (x, y)."""
    centre = [float(xy[0]), float(xy[1]), 4.0]
    params[key] = mi.Point3f(*centre) if key.endswith("center") else T().translate(centre).scale(0.3)
    params.update()
    return np.array(mi.render(scene, seed=0, spp=8))


target = render([0.3, -0.2])


def loss(xy):
    return float(np.mean((render(xy) - target) ** 2))


budget = int(sys.argv[1]) if len(sys.argv) > 1 else 400
start = [-0.5, 0.4]
print(f"start: loss {loss(start):.3e}")
# The box keeps the shadow in the picture: a picture without the ball's shadow would be a
# cheaper wrong answer. sigma0, the first spread, is half the box's width.
best = plateau_free.minimize(loss, start, budget=budget, seed=0, bounds=[(-0.5, 0.5)] * 2, sigma0=0.5)
print(f"after {best.nfev} renders: ball at {best.x.round(3)}, loss {best.fun:.3e} (target (0.3, -0.2))")
assert best.fun == 0.0  # the same image as the target's, with the same seed
