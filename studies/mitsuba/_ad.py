"""Mitsuba's own gradient on SHADOW (part of optimize.py): a differentiable integrator,
Dr.Jit's backward pass and Mitsuba's Adam from the same start as plateau-free's runs."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from studies.mitsuba import _scene as ms  # imports no mitsuba itself
from studies.mitsuba._files import write_csv, write_png


def run_ad(mi, args, seed: int, out: Path) -> dict:
    import drjit as dr
    import numpy as np

    name = args.ad_integrator
    integrator = {"type": name}
    if not name.startswith("direct"):
        integrator["max_depth"] = ms.MAX_DEPTH
    scene = ms.ShadowScene(mi, spp=args.spp, scale=args.scale, integrator=integrator)
    scene.set_theta(ms.TARGET)
    reference = mi.render(scene.scene, seed=seed, spp=args.spp)  # the same integrator and seed
    ref_path = ms.ShadowScene(mi, spp=args.spp, scale=args.scale)
    path_reference = ref_path.render(ms.TARGET, seed)

    opt = mi.ad.Adam(lr=args.lr)
    opt["theta"] = mi.Vector2f(*ms.START)
    params = scene.params
    base = ms.sphere_base()  # the centre at theta = (0, 0), from `pathtracer export shadow`
    rows = []
    t_start = time.perf_counter()
    for it in range(args.ad_iterations):
        theta = opt["theta"]
        params[scene.key] = mi.Transform4f().translate(
            mi.Vector3f(base[0], base[1] + theta.x, base[2] + theta.y)
        ).scale(ms.SPHERE_RADIUS)
        params.update()
        image = mi.render(scene.scene, params, seed=seed, spp=args.spp)
        loss = dr.mean(dr.square(image - reference), axis=None)
        dr.backward(loss)
        grad = np.array(dr.grad(opt["theta"]), dtype=np.float64).ravel()
        th = np.array(theta, dtype=np.float64).ravel()
        opt.step()
        rows.append({
            "iteration": it,
            "loss": float(np.array(loss).ravel()[0]),
            "param_mse": ms.param_mse(th),
            "seconds": time.perf_counter() - t_start,
            "theta0": float(th[0]),
            "theta1": float(th[1]),
            "grad0": float(grad[0]),
            "grad1": float(grad[1]),
        })
        print(f"  AD {name} iteration {it}: loss {rows[-1]['loss']:.4e} param MSE "
              f"{rows[-1]['param_mse']:.3e} ({rows[-1]['seconds']:.0f} s)", file=sys.stderr, flush=True)
        if args.ad_seconds and rows[-1]["seconds"] >= args.ad_seconds:
            break
    seconds = time.perf_counter() - t_start
    final_theta = np.array(opt["theta"], dtype=np.float64).ravel()
    final = ref_path.render(final_theta, seed)
    write_png(mi, final, out / "ad_final.png")
    write_csv(out / "ad_history.csv", rows)
    done = len(rows)
    return {
        "mitsuba_ad_integrator": name,
        "mitsuba_ad_iterations": done,
        "mitsuba_ad_lr": args.lr,
        "mitsuba_ad_initial_loss": rows[0]["loss"] if rows else None,
        "mitsuba_ad_final_loss": rows[-1]["loss"] if rows else None,
        "mitsuba_ad_param_mse": ms.param_mse(final_theta),
        "mitsuba_ad_image_mse": ms.image_mse(final, path_reference),
        "mitsuba_ad_seconds_per_iteration": seconds / max(done, 1),
        "mitsuba_ad_final_theta": [float(v) for v in final_theta],
        "mitsuba_ad_note": (
            f"Mitsuba's own gradient ({name}, Adam, LR {args.lr}) ran {done} iterations, not "
            f"{args.iterations}: it costs {seconds / max(done, 1):.1f} s an iteration here. Its loss is "
            f"against a target rendered with the same integrator and seed; mitsuba_ad_image_mse is "
            f"the final parameters rendered with the path integrator against the plateau run's target."
        ),
    }


def ad_keys(ad: dict) -> dict:
    keys = {k: v for k, v in ad.items() if k.startswith("mitsuba_ad_")}
    keys["mitsuba_ad_dir"] = "../ad"
    return keys
