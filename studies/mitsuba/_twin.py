"""A task's Mitsuba twin that moves with theta as the task says (``pathtracer export``).

``Twin(mi, task)`` loads the task's exported scene at its start once; ``set_theta(theta)``
asks the exporter for the scene at theta (``pathtracer export TASK --params-file FILE``, a
few milliseconds) and writes what changed into the loaded scene through ``mi.traverse``: a
sphere's or a quad's ``to_world``, a box's or a mesh's vertices (moved from the start's by
the change of its ``to_world``), a material's albedo, a texture's texels (TEXTURE's bitmap,
read from the exporter's image), an emitter's radiance, a point light. No scene reload, no
second description of how the parameters move the scene.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
from typing import Any

import numpy as np

from studies.mitsuba import _export as mx


def _affine(rows) -> np.ndarray:
    m = np.eye(4)
    m[:3, :] = np.asarray(rows, dtype=np.float64)
    return m


def task_box(defaults: dict[str, Any], n: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The task's box for ``n`` parameters from its exported ``defaults``, as the path tracer
    uses it: [0, 1] per parameter but [-1, 2] for an angle of period 1 (``periodic``: a period
    each side, so the seam is no wall); None when the task is unbounded."""
    if not defaults["unit_box"]:
        return None
    lower, upper = np.zeros(n), np.ones(n)
    for i in defaults.get("periodic", []):
        lower[i], upper[i] = -1.0, 2.0
    return lower, upper


def param_mse(x, target, defaults: dict[str, Any]) -> float:
    """The path tracer's parameter error: the plain mean of squared differences, with each
    periodic parameter outside [0, 1] first brought into [0, 1) by whole periods (the same
    scene)."""
    x = np.array(x, dtype=np.float64)
    for i in defaults.get("periodic", []):
        if not 0.0 <= x[i] <= 1.0:
            x[i] = x[i] % 1.0
    return float(np.mean((x - np.asarray(target, dtype=np.float64)) ** 2))


def export_at(task: str, theta, spp: int | None = None, scale: float | None = None,
              mi=None) -> dict[str, Any]:
    """The task's description at ``theta``; with ``mi``, its textures' texels as arrays in
    ``desc["texels"]`` (the exporter's side files are not kept)."""
    with tempfile.TemporaryDirectory() as tmp:
        params = os.path.join(tmp, "params.json")
        with open(params, "w") as f:
            json.dump([float(t) for t in theta], f)
        out = os.path.join(tmp, "out")
        cmd = [mx.pathtracer_binary(), "export", task, "--params-file", params, "--out", out]
        if spp is not None:
            cmd += ["--spp", str(spp)]
        if scale is not None:
            cmd += ["--scale", repr(float(scale))]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        desc = mx.read_description(out)
        if mi is not None:
            desc["texels"] = [np.array(mi.Bitmap(os.path.join(out, t["file"])), dtype=np.float32)
                              for t in desc["textures"]]
        return desc


class Twin:
    """The Mitsuba scene of ``task``, movable: ``render(theta, seed)`` -> linear RGB image."""

    def __init__(self, mi, task: str, spp: int | None = None, scale: float | None = None,
                 integrator: dict[str, Any] | None = None):
        self.mi, self.task, self.scale = mi, task, scale
        with tempfile.TemporaryDirectory() as tmp:
            desc = mx.run_export(task, tmp, "start", spp=spp, scale=scale)
            self.theta = mx.theta_of(desc)
            self.spp = int(desc["spp"])
            # optimize=False: Mitsuba would merge meshes sharing a BSDF, and each box must move alone.
            self.scene = mi.load_dict(mx.scene_dict(mi, desc, self.spp, integrator), optimize=False)
        self.params = mi.traverse(self.scene)
        self.desc = desc
        self._local: dict[str, np.ndarray] = {}
        for k, s in enumerate(desc["shapes"]):
            if s["type"] in ("box", "mesh"):
                key = self._name(k) + ".vertex_positions"
                world = np.array(self.params[key], dtype=np.float64).reshape(-1, 3)
                inv = np.linalg.inv(_affine(s["to_world"]))
                self._local[key] = world @ inv[:3, :3].T + inv[:3, 3]

    def _name(self, k: int) -> str:
        return f"shape_{k:04d}_{self.desc['shapes'][k]['type']}"

    def _set_shape(self, k: int, s: dict[str, Any]) -> None:
        mi, name = self.mi, self._name(k)
        if s["type"] == "sphere":
            self.params[name + ".to_world"] = mi.Transform4f().translate(s["center"]).scale(s["radius"])
        elif s["type"] == "quad":
            self.params[name + ".to_world"] = mi.Transform4f(
                [list(r) for r in mx.quad_to_world(s["origin"], s["u"], s["v"])] + [[0.0, 0.0, 0.0, 1.0]])
        else:
            key = name + ".vertex_positions"
            m = _affine(s["to_world"])
            self.params[key] = mi.Float((self._local[key] @ m[:3, :3].T + m[:3, 3]).ravel().astype(np.float32))
        if "emission" in s:
            self.params[name + ".emitter.radiance.value"] = mi.Color3f(*s["emission"])

    def _set_materials(self, old: dict[str, Any], new: dict[str, Any]) -> None:
        for m, (a, b) in enumerate(zip(old["materials"], new["materials"])):
            if b["type"] != "diffuse":
                continue
            texels = new["texels"][b["texture"]] if "texture" in b else None
            if a == b and texels is None:
                continue
            for k, s in enumerate(new["shapes"]):
                if s["material"] != m:
                    continue
                reflectance = self._name(k) + ".bsdf.brdf_0.reflectance"
                if texels is not None:
                    # The texture's texels are the parameters (TEXTURE): a new bitmap every move.
                    self.params[reflectance + ".data"] = self.mi.TensorXf(texels)
                else:
                    self.params[reflectance + ".value"] = self.mi.Color3f(*b["albedo"])

    def set_theta(self, theta) -> None:
        """Moves the scene to ``theta`` (what the exporter says changed)."""
        theta = [float(t) for t in theta]
        if theta == self.theta:
            return
        new = export_at(self.task, theta, self.spp, self.scale, mi=self.mi)
        old = self.desc
        for k, (a, b) in enumerate(zip(old["shapes"], new["shapes"])):
            if {x: y for x, y in a.items() if x != "material"} != {x: y for x, y in b.items() if x != "material"}:
                self._set_shape(k, b)
        self._set_materials(old, new)
        for k, (a, b) in enumerate(zip(old["point_lights"], new["point_lights"])):
            if a != b:
                self.params[f"point_{k}.position"] = self.mi.Point3f(*b["position"])
                self.params[f"point_{k}.intensity.value"] = self.mi.Color3f(*b["intensity"])
        if old["environment"] != new["environment"] and "environment.radiance.value" in self.params:
            self.params["environment.radiance.value"] = self.mi.Color3f(*new["environment"])
        self.params.update()
        self.desc, self.theta = new, theta

    def render(self, theta, seed: int = 0) -> np.ndarray:
        """The image at ``theta`` with Mitsuba's ``seed``, float64 (height, width, 3)."""
        self.set_theta(theta)
        img = self.mi.render(self.scene, seed=int(seed) & 0xFFFFFFFF, spp=self.spp)
        return np.array(img, dtype=np.float64)
