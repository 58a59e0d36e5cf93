"""A task's scene as our renderer exports it (``pathtracer export``), loaded into Mitsuba 3.

``pathtracer export TASK --out DIR`` writes ``DIR/scene.json`` (format "pathtracer-scene 1",
examples/pathtracer/src/export.rs) from the very scene our renderer draws; this module turns
it into a Mitsuba scene dictionary, so that a scene is described once, in the task's Rust file.
Where Mitsuba needs another but equivalent choice, the choice is made here and explained in
docs/tasks.md ("The same scenes in Mitsuba 3"):

* a diffuse material becomes ``twosided`` ``diffuse`` (our Lambertian surfaces scatter on
  both sides; Mitsuba's ``diffuse`` alone is black from the back);
* a quad (corner, edges u and v) becomes a ``rectangle`` whose ``to_world`` has columns u/2,
  v/2, u x v normalised and the centre: Mitsuba's rectangle is [-1, 1]^2 in local x and y with
  normal +z and uv = (x + 1) / 2, (y + 1) / 2, which is our quad with our uv;
* a box is a ``cube`` ([-1, 1]^3) with the exported ``to_world``; a mesh an ``obj`` with
  ``face_normals`` (we shade with the triangle's own normal);
* a texture is a ``bitmap`` read ``raw`` (linear, no sRGB decoding), ``bilinear``, ``clamp``;
* the camera is a ``perspective`` sensor with ``fov_axis`` x and a ``box`` pixel filter;
* the integrator is ``path`` with the exported ``max_depth``.

The module needs only numpy and mitsuba; ``run_export`` runs the pathtracer binary.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import Any

FORMAT = "pathtracer-scene 1"


def read_description(directory: str | os.PathLike[str]) -> dict[str, Any]:
    """``DIR/scene.json``, with its format checked; side files are resolved against ``DIR``."""
    path = Path(directory) / "scene.json"
    with open(path) as f:
        desc: dict[str, Any] = json.load(f)
    if desc.get("format") != FORMAT:
        raise ValueError(f"{path}: format {desc.get('format')!r}, expected {FORMAT!r}")
    desc["_dir"] = str(Path(directory).resolve())
    return desc


def theta_of(desc: dict[str, Any]) -> list[float]:
    """The description's parameters: ``theta``, or a large task's side file ``theta_file``."""
    if "theta" in desc:
        return [float(t) for t in desc["theta"]]
    with open(Path(desc["_dir"]) / desc["theta_file"]) as f:
        return [float(t) for t in json.load(f)]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _matrix(mi, rows):
    """A 3x4 affine matrix (three rows of four) as Mitsuba's 4x4 transform."""
    return mi.ScalarTransform4f(list(rows) + [[0.0, 0.0, 0.0, 1.0]])


def quad_to_world(origin, u, v) -> list[list[float]]:
    """The 3x4 matrix mapping Mitsuba's rectangle [-1, 1]^2 (normal +z) onto our quad."""
    n = _cross(u, v)
    length = sum(c * c for c in n) ** 0.5
    n = [c / length for c in n]
    center = [origin[i] + 0.5 * u[i] + 0.5 * v[i] for i in range(3)]
    return [[0.5 * u[i], 0.5 * v[i], n[i], center[i]] for i in range(3)]


def _rgb(value) -> dict[str, Any]:
    return {"type": "rgb", "value": [float(c) for c in value]}


def _bsdf(desc: dict[str, Any], k: int) -> dict[str, Any]:
    m = desc["materials"][k]
    if m["type"] == "dielectric":
        return {"type": "dielectric", "int_ior": float(m["ior"]), "ext_ior": 1.0}
    if m["type"] != "diffuse":
        raise ValueError(f"material {k}: unknown type {m['type']!r}")
    if "texture" in m:
        tex = desc["textures"][m["texture"]]
        reflectance: dict[str, Any] = {
            "type": "bitmap",
            "filename": os.path.join(desc["_dir"], tex["file"]),
            "raw": True,
            "filter_type": "bilinear",
            "wrap_mode": "clamp",
        }
    else:
        reflectance = _rgb(m["albedo"])
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": reflectance}}


def _shape(mi, desc: dict[str, Any], s: dict[str, Any]) -> dict[str, Any]:
    kind = s["type"]
    if kind == "sphere":
        out: dict[str, Any] = {"type": "sphere", "center": [float(c) for c in s["center"]],
                               "radius": float(s["radius"])}
    elif kind == "quad":
        out = {"type": "rectangle", "to_world": _matrix(mi, quad_to_world(s["origin"], s["u"], s["v"]))}
        if "emission" in s:
            out["emitter"] = {"type": "area", "radiance": _rgb(s["emission"])}
    elif kind == "box":
        out = {"type": "cube", "to_world": _matrix(mi, s["to_world"])}
    elif kind == "mesh":
        out = {"type": "obj", "filename": os.path.join(desc["_dir"], s["file"]),
               "face_normals": True, "to_world": _matrix(mi, s["to_world"])}
    else:
        raise ValueError(f"unknown shape type {kind!r}")
    out["bsdf"] = _bsdf(desc, s["material"])
    return out


def _sensor(mi, desc: dict[str, Any], spp: int) -> dict[str, Any]:
    cam = desc["camera"]
    origin = [float(c) for c in cam["origin"]]
    target = [origin[i] + float(cam["forward"][i]) for i in range(3)]
    return {
        "type": "perspective",
        "fov": float(cam["hfov_degrees"]),
        "fov_axis": "x",
        "to_world": mi.ScalarTransform4f().look_at(origin=origin, target=target, up=cam["up"]),
        "sampler": {"type": "independent", "sample_count": spp},
        "film": {
            "type": "hdrfilm",
            "width": int(desc["film"]["width"]),
            "height": int(desc["film"]["height"]),
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
        },
    }


def scene_dict(mi, desc: dict[str, Any], spp: int | None = None,
               integrator: dict[str, Any] | None = None) -> dict[str, Any]:
    """The Mitsuba scene dictionary of an exported description (``read_description``)."""
    spp = int(spp or desc["spp"])
    scene: dict[str, Any] = {
        "type": "scene",
        "integrator": integrator or {"type": "path", "max_depth": int(desc["max_depth"])},
        "sensor": _sensor(mi, desc, spp),
    }
    for k, s in enumerate(desc["shapes"]):
        scene[f"shape_{k:04d}_{s['type']}"] = _shape(mi, desc, s)
    for k, light in enumerate(desc["point_lights"]):
        scene[f"point_{k}"] = {"type": "point", "position": [float(c) for c in light["position"]],
                               "intensity": _rgb(light["intensity"])}
    if any(float(c) != 0.0 for c in desc["environment"]):
        scene["environment"] = {"type": "constant", "radiance": _rgb(desc["environment"])}
    return scene


def pathtracer_binary() -> str:
    """The pathtracer command: ``$PATHTRACER``, else target/release/pathtracer of this clone."""
    given = os.environ.get("PATHTRACER")
    if given:
        return given
    return str(Path(__file__).resolve().parents[2] / "target" / "release" / "pathtracer")


def run_export(task: str, out: str | os.PathLike[str], which: str = "target",
               spp: int | None = None, scale: float | None = None) -> dict[str, Any]:
    """Runs ``pathtracer export TASK --initial|--target --out OUT`` and reads the result."""
    if which not in ("start", "target"):
        raise ValueError(f"which: {which!r}; allowed: start, target")
    cmd = [pathtracer_binary(), "export", task, "--initial" if which == "start" else "--target",
           "--out", str(out)]
    if spp is not None:
        cmd += ["--spp", str(spp)]
    if scale is not None:
        cmd += ["--scale", repr(float(scale))]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return read_description(out)


def render(mi, desc: dict[str, Any], seed: int = 0, spp: int | None = None):
    """Mitsuba's linear RGB image of the description, as a float64 numpy array (H, W, 3)."""
    import numpy as np

    scene = mi.load_dict(scene_dict(mi, desc, spp))
    img = mi.render(scene, seed=int(seed) & 0xFFFFFFFF, spp=int(spp or desc["spp"]))
    return np.array(img, dtype=np.float64)
