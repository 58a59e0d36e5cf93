"""Mitsuba's own gradient of a task's image loss with respect to the task's parameters theta.

The scene is the exporter's (``pathtracer export``, _export.py), and so is the map
theta -> scene: ``ChainTwin`` flattens every number of an exported description (sphere
centres and radii, quad corners and edges, box and mesh ``to_world`` rows, albedos, emissions,
point lights) into a vector e(theta), and takes its Jacobian J = de/dtheta from the exporter
by central differences (``step``; the exporter computes the scene in f32, so the step must be
large enough for f32 rounding and small enough for the map's curvature: ``jacobian_error``
measures both). A render at theta then uses the numbers

    e = e(theta0) + J (theta - theta0)         (theta a Dr.Jit leaf, theta0 = theta's value)

written into the loaded Mitsuba scene by Dr.Jit expressions (a sphere's ``to_world`` from its
centre and radius, a quad's from its corner and edges, a box's or mesh's vertices from its
``to_world``), so its value is the export at theta and Dr.Jit's backward pass gives
dL/dtheta = J^T dL/de: the chain rule through Mitsuba's derivative of the render and the
exporter's derivative of the scene. Where the map is affine (J at the start equals J at the
target, as for translations) J is computed once; otherwise (rotations) at every theta.

TEXTURE's parameters are the texture's texels: there theta is the bitmap's data itself
(``TextureTwin``), the export is read once.
"""

from __future__ import annotations

import tempfile
from typing import Any

import numpy as np

from studies.mitsuba import _export as mx
from studies.mitsuba import _twin as mt

STEP = 1e-2  # the exporter's central-difference step in theta (see jacobian_error)


def integrator_dict(integrator: str | dict[str, Any], desc: dict[str, Any]) -> dict[str, Any]:
    """``{"type": name}`` or a given dictionary, with the export's ``max_depth``."""
    out = {"type": integrator} if isinstance(integrator, str) else dict(integrator)
    out["max_depth"] = int(desc["max_depth"])
    return out


def _shape_numbers(s: dict[str, Any]) -> list[tuple[str, list[float]]]:
    kind = s["type"]
    if kind == "sphere":
        out = [("center", s["center"]), ("radius", [s["radius"]])]
    elif kind == "quad":
        out = [("origin", s["origin"]), ("u", s["u"]), ("v", s["v"])]
        if "emission" in s:
            out.append(("emission", s["emission"]))
    else:
        out = [("to_world", [c for row in s["to_world"] for c in row])]
    return out


def layout(desc: dict[str, Any]) -> list[tuple[tuple[str, int, str], list[float]]]:
    """Every number of a description that a parameter could move, keyed (kind, index, field)."""
    items: list[tuple[tuple[str, int, str], list[float]]] = []
    for k, s in enumerate(desc["shapes"]):
        items += [(("shape", k, f), [float(c) for c in v]) for f, v in _shape_numbers(s)]
    for m, mat in enumerate(desc["materials"]):
        if mat["type"] == "diffuse" and "texture" not in mat:
            items.append((("material", m, "albedo"), [float(c) for c in mat["albedo"]]))
    for k, light in enumerate(desc["point_lights"]):
        items.append((("point", k, "position"), [float(c) for c in light["position"]]))
        items.append((("point", k, "intensity"), [float(c) for c in light["intensity"]]))
    items.append((("environment", 0, "radiance"), [float(c) for c in desc["environment"]]))
    return items


def numbers(desc: dict[str, Any]) -> np.ndarray:
    """The description's numbers, flattened in ``layout`` order."""
    return np.concatenate([np.asarray(v, dtype=np.float64) for _, v in layout(desc)])


def jacobian(task: str, theta: np.ndarray, step: float, scale: float | None) -> tuple[np.ndarray, np.ndarray]:
    """(e(theta), de/dtheta by central differences of the exporter with ``step``)."""
    e0 = numbers(mt.export_at(task, theta, None, scale))
    jac = np.zeros((e0.size, theta.size))
    for i in range(theta.size):
        up, down = theta.copy(), theta.copy()
        up[i] += step
        down[i] -= step
        jac[:, i] = (numbers(mt.export_at(task, up, None, scale))
                     - numbers(mt.export_at(task, down, None, scale))) / (2.0 * step)
    return e0, jac


def jacobian_error(task: str, theta: np.ndarray, step: float, scale: float | None = None) -> float:
    """max |J(step) - J(step / 2)| / max |J|: small where ``step`` is in the flat-error range."""
    _, a = jacobian(task, theta, step, scale)
    _, b = jacobian(task, theta, step / 2.0, scale)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-30))


class ChainTwin:
    """The task's Mitsuba scene under a differentiable ``integrator``, moved by the exporter's map.

    ``loss_and_grad(theta, reference, seed)`` renders at theta with Mitsuba's ``seed``, returns
    the image MSE against ``reference`` and dL/dtheta (numpy, float64)."""

    def __init__(self, mi, task: str, integrator: str | dict[str, Any], spp: int | None = None,
                 scale: float | None = None, step: float = STEP):
        import drjit as dr

        self.mi, self.dr, self.task, self.scale, self.step = mi, dr, task, scale, step
        with tempfile.TemporaryDirectory() as tmp:
            desc = mx.run_export(task, tmp, "start", spp=spp, scale=scale)
            self.target = np.array(mx.run_export(task, tmp, "target", spp=spp, scale=scale)["theta"])
            self.spp = int(desc["spp"])
            integ = integrator_dict(integrator, desc)
            self.scene = mi.load_dict(mx.scene_dict(mi, desc, self.spp, integ), optimize=False)
        self.desc, self.defaults = desc, desc["defaults"]
        self.start = np.array(desc["theta"], dtype=np.float64)
        self.params = mi.traverse(self.scene)
        self._slots = self._slot_table(desc)
        self._local = self._local_vertices(desc)
        e0, j0 = jacobian(task, self.start, step, scale)
        _, j1 = jacobian(task, self.target, step, scale)
        self.affine = bool(np.allclose(j0, j1, rtol=1e-3, atol=1e-4 * max(np.max(np.abs(j0)), 1e-30)))
        self._lin = (self.start.copy(), e0, j0)
        # What moves: numbers with a nonzero derivative here or a change between start and target.
        moved = (np.abs(j0).max(axis=1) > 0) | (np.abs(j1).max(axis=1) > 0)
        self.moving = [key for key, (lo, hi) in self._slots.items() if moved[lo:hi].any()]
        if not self.moving:
            raise ValueError(f"task {task!r}: no exported number moves with theta")

    @staticmethod
    def _slot_table(desc) -> dict[tuple[str, int, str], tuple[int, int]]:
        slots, at = {}, 0
        for key, v in layout(desc):
            slots[key] = (at, at + len(v))
            at += len(v)
        return slots

    def _name(self, k: int) -> str:
        return f"shape_{k:04d}_{self.desc['shapes'][k]['type']}"

    def _local_vertices(self, desc) -> dict[int, np.ndarray]:
        local = {}
        for k, s in enumerate(desc["shapes"]):
            if s["type"] in ("box", "mesh"):
                world = np.array(self.params[self._name(k) + ".vertex_positions"], dtype=np.float64).reshape(-1, 3)
                inv = np.linalg.inv(mt._affine(s["to_world"]))
                local[k] = world @ inv[:3, :3].T + inv[:3, 3]
        return local

    def linearisation(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(theta0, e(theta0), J(theta0)): at the start when the map is affine, else at theta."""
        if not self.affine and not np.array_equal(theta, self._lin[0]):
            e0, j = jacobian(self.task, theta, self.step, self.scale)
            self._lin = (theta.copy(), e0, j)
        return self._lin

    def _numbers(self, theta_dr, theta: np.ndarray, jac_scale: float = 1.0):
        """e = e(theta0) + J (theta - theta0) as a Dr.Jit Float (differentiable in theta_dr);
        ``jac_scale`` scales its derivative, not its value (the test's broken chain rule)."""
        dr, mi = self.dr, self.mi
        t0, e0, jac = self.linearisation(theta)
        rows, cols = np.nonzero(jac)
        e = mi.Float(e0.astype(np.float32))
        if rows.size:
            d = theta_dr - mi.Float(t0.astype(np.float32))
            if jac_scale != 1.0:
                # the same value, the derivative jac_scale x J: adds (jac_scale - 1) J (theta - theta's value)
                d = d + (jac_scale - 1.0) * (theta_dr - mi.Float(theta.astype(np.float32)))
            vals = dr.gather(mi.Float, d, mi.UInt32(cols.astype(np.uint32))) * mi.Float(
                jac[rows, cols].astype(np.float32))
            dr.scatter_reduce(dr.ReduceOp.Add, e, vals, mi.UInt32(rows.astype(np.uint32)))
        return e

    def _get(self, e, key, j: int):
        lo, _ = self._slots[key]
        return self.dr.gather(self.mi.Float, e, self.mi.UInt32(lo + j))

    def _vec(self, e, key):
        return self.mi.Vector3f(*(self._get(e, key, j) for j in range(3)))

    def _write(self, e) -> None:
        for key in self.moving:
            kind, k, field = key
            if kind == "shape":
                self._write_shape(e, k, field)
            elif kind == "material":
                for i, s in enumerate(self.desc["shapes"]):
                    if s["material"] == k:
                        self.params[self._name(i) + ".bsdf.brdf_0.reflectance.value"] = self.mi.Color3f(
                            *(self._get(e, key, j) for j in range(3)))
            else:
                raise ValueError(f"task {self.task!r}: {key} moves with theta, and Mitsuba does not "
                                 "differentiate it (a point light or the environment)")
        self.params.update()

    def _write_shape(self, e, k: int, field: str) -> None:
        mi, dr, name, key = self.mi, self.dr, self._name(k), ("shape", k, field)
        kind = self.desc["shapes"][k]["type"]
        if kind == "sphere" and field in ("center", "radius"):
            r = self._get(e, ("shape", k, "radius"), 0)
            self.params[name + ".to_world"] = mi.Transform4f().translate(
                self._vec(e, ("shape", k, "center"))).scale(mi.Vector3f(r, r, r))
        elif kind == "quad" and field in ("origin", "u", "v"):
            o, u, v = (self._vec(e, ("shape", k, f)) for f in ("origin", "u", "v"))
            n = dr.normalize(dr.cross(u, v))
            c = o + 0.5 * u + 0.5 * v
            m = mi.Matrix4f(0.5 * u.x, 0.5 * v.x, n.x, c.x, 0.5 * u.y, 0.5 * v.y, n.y, c.y,
                            0.5 * u.z, 0.5 * v.z, n.z, c.z, 0.0, 0.0, 0.0, 1.0)
            self.params[name + ".to_world"] = mi.Transform4f(m)
        elif field == "emission":
            self.params[name + ".emitter.radiance.value"] = mi.Color3f(*(self._get(e, key, j) for j in range(3)))
        elif field == "to_world":
            loc = self._local[k]
            m = [[self._get(e, key, 4 * r + c) for c in range(4)] for r in range(3)]
            cols = [mi.Float(loc[:, c].astype(np.float32)) for c in range(3)]
            world = [m[r][0] * cols[0] + m[r][1] * cols[1] + m[r][2] * cols[2] + m[r][3] for r in range(3)]
            flat = dr.zeros(mi.Float, 3 * loc.shape[0])
            idx = dr.arange(mi.UInt32, loc.shape[0])
            for r in range(3):
                dr.scatter(flat, world[r], 3 * idx + r)
            self.params[name + ".vertex_positions"] = flat

    def set_numbers(self, desc: dict[str, Any]) -> None:
        """Writes a description's numbers (no gradient): e.g. the target's, for the reference."""
        self._write(self.mi.Float(numbers(desc).astype(np.float32)))

    def render(self, theta: np.ndarray, seed: int) -> np.ndarray:
        """The primal image at theta (exact export), float64 (height, width, 3)."""
        self.set_numbers(mt.export_at(self.task, theta, self.spp, self.scale))
        img = self.mi.render(self.scene, seed=int(seed) & 0xFFFFFFFF, spp=self.spp)
        return np.array(img, dtype=np.float64)

    def loss_and_grad(self, theta: np.ndarray, reference, seed: int, jac_scale: float = 1.0,
                      seed_grad: int | None = None) -> tuple[float, np.ndarray, np.ndarray]:
        """(image MSE, dL/dtheta, the image) at theta; ``jac_scale`` != 1 breaks the chain
        rule on purpose (the test's negative control). ``seed_grad``: the seed of Mitsuba's
        adjoint pass (None: Mitsuba's default, decorrelated from ``seed``, which estimates the
        gradient of the mean image's loss; ``seed``: the derivative of this very render's loss)."""
        dr, mi = self.dr, self.mi
        theta = np.asarray(theta, dtype=np.float64)
        theta_dr = mi.Float(theta.astype(np.float32))
        dr.enable_grad(theta_dr)
        self._write(self._numbers(theta_dr, theta, jac_scale))
        img = mi.render(self.scene, self.params, seed=int(seed) & 0xFFFFFFFF, spp=self.spp,
                        seed_grad=0 if seed_grad is None else int(seed_grad) & 0xFFFFFFFF)
        loss = dr.mean(dr.square(img - reference), axis=None)
        dr.backward(loss)
        grad = np.array(dr.grad(theta_dr), dtype=np.float64)
        return float(np.array(loss).ravel()[0]), grad, np.array(dr.detach(img), dtype=np.float64)


class TextureTwin:
    """TEXTURE: theta is the bitmap's data (128 x 128 x 3 texels in [0, 1]), differentiated directly."""

    def __init__(self, mi, integrator: str | dict[str, Any], spp: int | None = None, scale: float | None = None):
        import drjit as dr

        self.mi, self.dr, self.task = mi, dr, "texture"
        with tempfile.TemporaryDirectory() as tmp:
            desc = mx.run_export("texture", tmp, "start", spp=spp, scale=scale)
            self.spp = int(desc["spp"])
            integ = integrator_dict(integrator, desc)
            self.scene = mi.load_dict(mx.scene_dict(mi, desc, self.spp, integ), optimize=False)
            self.params = mi.traverse(self.scene)
            self.key = next(k for k in self.params.keys() if k.endswith("reflectance.data"))
            self.start = np.array(self.params[self.key], dtype=np.float64)
            tdesc = mx.run_export("texture", tmp, "target", spp=spp, scale=scale)
            tscene = mi.load_dict(mx.scene_dict(mi, tdesc, self.spp), optimize=False)
            self.target = np.array(mi.traverse(tscene)[self.key], dtype=np.float64)
        self.desc, self.defaults, self.affine = desc, desc["defaults"], True

    def _set(self, theta: np.ndarray):
        data = self.mi.TensorXf(np.asarray(theta, dtype=np.float32))
        self.params[self.key] = data
        self.params.update()
        return self.params[self.key]

    def render(self, theta: np.ndarray, seed: int) -> np.ndarray:
        self._set(theta)
        return np.array(self.mi.render(self.scene, seed=int(seed) & 0xFFFFFFFF, spp=self.spp), dtype=np.float64)

    def loss_and_grad(self, theta: np.ndarray, reference, seed: int, jac_scale: float = 1.0,
                      seed_grad: int | None = None) -> tuple[float, np.ndarray, np.ndarray]:
        dr, mi = self.dr, self.mi
        data = self._set(theta)
        dr.enable_grad(data)
        self.params.update()
        img = mi.render(self.scene, self.params, seed=int(seed) & 0xFFFFFFFF, spp=self.spp,
                        seed_grad=0 if seed_grad is None else int(seed_grad) & 0xFFFFFFFF)
        loss = dr.mean(dr.square(img - reference), axis=None)
        dr.backward(loss)
        grad = jac_scale * np.array(dr.grad(data), dtype=np.float64)
        dr.disable_grad(data)
        return float(np.array(loss).ravel()[0]), grad, np.array(dr.detach(img), dtype=np.float64)


def _sci(v) -> str:
    return "[" + ", ".join(f"{x:.2e}" for x in np.ravel(v)) + "]"


def compare_guiding(mi, task: str = "gi", theta=(0.2, 0.8, 0.2, 0.5, 0.8, 0.7), idx=(0, 1),
                    scale: float = 0.25, spp: int = 64, h: float = 0.02, seeds=(10, 11),
                    guidings=("grid", "none")) -> list[str]:
    """prb_projective's chained gradient per ``guiding`` against a central difference of the
    loss (GI's light position by default: a derivative made only of boundary terms, since the
    light is seen only by the light it casts). Lines of text, one per guiding and the FD."""
    theta = np.array(theta, dtype=np.float64)
    lines, reference = [], None
    for guiding in guidings:
        twin = ChainTwin(mi, task, {"type": "prb_projective", "guiding": guiding}, spp=spp, scale=scale)
        if reference is None:
            reference = twin.render(twin.target, 0)
        ref = mi.TensorXf(reference.astype(np.float32))
        g = np.mean([twin.loss_and_grad(theta, ref, s)[1][list(idx)] for s in seeds], axis=0)
        lines.append(f"guiding {guiding}: dL/dtheta{list(idx)} = {_sci(g)}")
    fd = []
    for s in seeds:
        row = []
        for i in idx:
            up, down = theta.copy(), theta.copy()
            up[i] += h
            down[i] -= h
            row.append((np.mean((twin.render(up, s) - reference) ** 2)
                        - np.mean((twin.render(down, s) - reference) ** 2)) / (2 * h))
        fd.append(row)
    lines.append(f"central difference (step {h}): {_sci(np.mean(fd, axis=0))}")
    return lines


if __name__ == "__main__":
    # python studies/mitsuba/_chain.py: the guiding comparison quoted in docs/mitsuba.md
    from studies.mitsuba._scene import load_mitsuba

    m = load_mitsuba()
    m.set_log_level(m.LogLevel.Error)
    print("\n".join(compare_guiding(m)))
