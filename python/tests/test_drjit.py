"""plateau_free.drjit.PlateauFreeOp: our gradient for some parameters and Dr.Jit's (Mitsuba's) for
the others, in one backward pass; and studies/mitsuba/mixed.py, small.

Needs drjit and mitsuba (scripts/install-mitsuba): skipped without them, a failure when
PLATEAU_FREE_REQUIRE_MITSUBA=1 (as the test command sets it).
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import sys
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np
import pytest

import plateau_free

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository: `studies`

HAVE_MITSUBA = importlib.util.find_spec("mitsuba") is not None
REQUIRE = os.environ.get("PLATEAU_FREE_REQUIRE_MITSUBA") == "1"
pytestmark = pytest.mark.skipif(
    not HAVE_MITSUBA and not REQUIRE,
    reason="mitsuba is not installed (scripts/install-mitsuba; PLATEAU_FREE_REQUIRE_MITSUBA=1 makes this a failure)",
)


@pytest.fixture(scope="module")
def mi() -> Iterator[Any]:
    from studies.mitsuba import _scene as ms

    yield ms.load_mitsuba()  # sets the variant and DRJIT_LIBLLVM_PATH


def phi(z: float) -> float:
    return math.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi)


def backward_theta(mi: Any, op: Any, theta: np.ndarray, weights: np.ndarray, sigma: float) -> np.ndarray:
    """One backward pass of ``sum(weights * op(theta, image))``: theta's gradient."""
    import drjit as dr

    t = mi.Float(theta)
    dr.enable_grad(t)
    image = op(t, mi.Float(np.zeros(len(weights))), sigma)
    dr.backward(dr.sum(image * mi.Float(weights)))
    return np.array(dr.grad(t), dtype=np.float64)


def mean_gradient(mi: Any, render: Callable[..., Any], theta: float, sigma: float) -> tuple[float, float]:
    from plateau_free.drjit import PlateauFreeOp

    op = PlateauFreeOp(render, samples=4, seed=7)
    draws = [backward_theta(mi, op, np.array([theta]), np.ones(1), sigma)[0] for _ in range(3000)]
    return float(np.mean(draws)), float(np.std(draws, ddof=1) / math.sqrt(len(draws)))


def test_the_mean_gradient_is_the_smoothed_gradient_of_a_step_and_a_staircase(mi: Any) -> None:
    a = 0.3
    step = lambda x, s: np.array([1.0 if x[0] > a else 0.0])  # noqa: E731
    stairs = lambda x, s: np.array([math.floor(x[0])])  # noqa: E731
    for theta, sigma in [(0.0, 0.5), (1.0, 0.4)]:
        mean, se = mean_gradient(mi, step, theta, sigma)
        exact = phi((theta - a) / sigma) / sigma
        # 4 standard errors, and the float32 rounding of each draw (Dr.Jit's Float).
        assert abs(mean - exact) < 4 * se + 1e-6, (theta, sigma, mean, se, exact)
    for theta, sigma in [(0.5, 0.3), (2.2, 0.7)]:
        mean, se = mean_gradient(mi, stairs, theta, sigma)
        exact = sum(phi((theta - k) / sigma) / sigma for k in range(-20, 21))
        assert abs(mean - exact) < 4 * se + 1e-6, (theta, sigma, mean, se, exact)


def test_each_backward_pass_is_the_estimators_estimate_on_the_same_seed(mi: Any) -> None:
    from plateau_free.drjit import PlateauFreeOp

    def render(x: np.ndarray, seed: int) -> np.ndarray:
        return np.array([float(x[0] + 2 * x[1] > 0.3), math.floor(3 * x[0]), seed % 7 / 7.0])

    weights = np.array([0.5, -1.25, 2.0])
    op = PlateauFreeOp(render, samples=6, seed=11)
    direct = plateau_free.PlateauFreeGradient(
        lambda x, s: float(np.dot(weights, render(x, s))), samples=6, seed=11, seeded=True
    )
    for k in range(5):
        theta = np.array([0.1 * k, -0.2], dtype=np.float32).astype(np.float64)
        expected = direct.estimate(theta, 0.4)
        got = backward_theta(mi, op, theta, weights, 0.4)
        # Dr.Jit's Float holds the float64 estimate rounded to float32: equal after rounding.
        assert np.array_equal(got.astype(np.float32), expected.astype(np.float32)), (k, got, expected)
    assert op.renders == 5 * 6
    # op.gradient itself: the float64 estimate, bit for bit.
    op2 = PlateauFreeOp(render, samples=6, seed=11)
    direct2 = plateau_free.PlateauFreeGradient(
        lambda x, s: float(np.dot(weights, render(x, s))), samples=6, seed=11, seeded=True
    )
    assert np.array_equal(op2.gradient([0.2, 0.1], weights, 0.3), direct2.estimate([0.2, 0.1], 0.3))


def test_one_backward_pass_gives_both_gradients_and_restores_theta(mi: Any) -> None:
    import drjit as dr
    from plateau_free.drjit import PlateauFreeOp

    restored = []
    op = PlateauFreeOp(lambda x, s: np.array([float(x[0] > 0.0), 0.0]), restore=restored.append, samples=2)
    theta, rho = mi.Float([0.1]), mi.Float([2.0, 3.0])
    dr.enable_grad(theta, rho)
    image = op(theta, rho * rho, 0.5)  # image = rho^2: its AD gradient is 2 rho v
    dr.backward(dr.sum(image * mi.Float([1.0, 10.0])))
    assert np.allclose(np.array(dr.grad(rho)), [4.0, 60.0])
    assert np.array(dr.grad(theta))[0] > 0.0
    assert len(restored) == 1 and np.array_equal(restored[0], np.array([0.1], dtype=np.float32))
    # The primal is the image, unchanged.
    assert np.array_equal(np.array(image), [4.0, 9.0])


def test_bad_input_is_an_error_naming_it(mi: Any) -> None:
    from plateau_free.drjit import PlateauFreeOp

    op = PlateauFreeOp(lambda x, s: np.zeros(3))
    for sigma in [0.0, -1.0, math.nan, math.inf]:
        with pytest.raises(ValueError, match="sigma"):
            op(mi.Float([0.0]), mi.Float([0.0, 0.0, 0.0]), sigma)
    with pytest.raises(ValueError, match="samples"):
        PlateauFreeOp(lambda x, s: np.zeros(1), samples=3)
    with pytest.raises(ValueError, match="render returned 3 values for an image of 2"):
        op.gradient([0.0], [1.0, 1.0], 0.5)


def test_the_mixed_example_runs_small(tmp_path: Path, mi: Any) -> None:
    from studies.mitsuba import mixed as mitsuba_mixed

    s = mitsuba_mixed.main(["--out", str(tmp_path), "--iterations", "6", "--scale", "0.125", "--spp", "2"])
    assert s["perturbed_renders"] == 6 * 2
    rows = (tmp_path / "history.csv").read_text().splitlines()
    assert len(rows) == 1 + 6
    assert json.loads((tmp_path / "summary.json").read_text())["param_mse"] == s["param_mse"]
    # Both kinds of gradient were there in the first backward pass, and the reflectance moved
    # towards its target.
    first = dict(zip(rows[0].split(","), rows[1].split(",")))
    assert float(first["grad_rho_r"]) != 0.0 and float(first["grad_theta0"]) != 0.0
    assert s["rho_max_error"] < 0.4
