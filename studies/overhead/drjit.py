"""What plateau_free.drjit.PlateauFreeOp costs over calling the estimator directly.

    target/venv/bin/python -m studies drjit-overhead   # after scripts/install-mitsuba

Times one backward pass through the op (``dr.custom``, ``dr.backward`` of a weighted sum, the
gradient read back) against ``PlateauFreeGradient.estimate`` on the same objective
``x -> <v, render(x)>``, with a render that costs next to nothing (a 64x48 RGB numpy image of a
step), 2 samples, best of 5 rounds of 200 passes. The difference is the op's own cost per
backward pass; a real render (tens of milliseconds and more) dwarfs it.
"""

from __future__ import annotations

import os
import time

import numpy as np

from studies.mitsuba import _scene as ms  # sets DRJIT_LIBLLVM_PATH through load_mitsuba


def main() -> None:
    mi = ms.load_mitsuba()
    import drjit as dr

    import plateau_free
    from plateau_free.drjit import PlateauFreeOp

    shape = (48, 64, 3)
    base = np.linspace(0.0, 1.0, int(np.prod(shape))).reshape(shape)

    def render(x: np.ndarray, seed: int) -> np.ndarray:
        return base * float(x[0] > 0.3)

    v = np.full(base.size, 1.0 / base.size)
    passes, rounds = 200, 5
    op_best = direct_best = float("inf")
    for _ in range(rounds):
        op = PlateauFreeOp(render, samples=2)
        weights = mi.TensorXf(v.reshape(shape))
        start = time.perf_counter()
        for _ in range(passes):
            theta = mi.Float([0.1, 0.0])
            dr.enable_grad(theta)
            image = op(theta, mi.TensorXf(np.zeros(shape)), 0.5)
            dr.backward(dr.sum(image * weights, axis=None))
            np.array(dr.grad(theta))
        op_best = min(op_best, (time.perf_counter() - start) / passes)
        est = plateau_free.PlateauFreeGradient(
            lambda x, s: float(np.dot(v, render(x, s).ravel())), samples=2, seeded=True
        )
        start = time.perf_counter()
        for _ in range(passes):
            est.estimate(np.array([0.1, 0.0]), 0.5)
        direct_best = min(direct_best, (time.perf_counter() - start) / passes)
    print(f"PlateauFreeOp backward pass: {op_best * 1e6:.0f} us; estimator directly: "
          f"{direct_best * 1e6:.0f} us; the op adds {(op_best - direct_best) * 1e6:.0f} us per pass "
          f"(64x48 RGB, 2 samples, best of {rounds} x {passes}; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")


if __name__ == "__main__":
    main()
