"""plateau_free.least_squares: the vector method for a fun that returns an array. It solves
linear least squares, leaves plateaus that the sum of squares alone would stall on, uses a
sparsity pattern given as pairs or a mask, keeps the budget and the box, gives the same bits
from the same seed as the Rust run asked and told directly, and refuses bad input with
ValueErrors that name it."""

import numpy as np
import pytest

import plateau_free
from plateau_free import _native


def test_linear_least_squares_reaches_the_normal_equations_solution():
    a = np.array([[1.0, 0.0], [1.0, 1.0], [1.0, 2.0], [1.0, 3.0]])
    y = np.array([1.0, 2.0, 2.0, 4.0])
    res = plateau_free.least_squares(lambda x: a @ x - y, [0.0, 0.0], budget=300, sigma0=0.5, seed=2)
    expected = np.linalg.lstsq(a, y, rcond=None)[0]
    assert np.allclose(res.x, expected, atol=1e-6), res.x
    assert res.fun == pytest.approx(float(np.sum((a @ expected - y) ** 2)), abs=1e-9)
    assert res.nfev <= 300 and res.nit >= 1 and res.njev >= 1
    assert res.residuals.shape == (4,)
    assert res.success is False and res.status == 1


def test_a_staircase_of_5000_parameters_with_a_diagonal_pattern():
    """Each output a rounded staircase of its parameter: zero derivative almost everywhere."""
    n = 5000
    target = (np.arange(n) % 10) / 10.0

    def fun(x):
        return np.round((x - target) * 20.0) / 20.0

    x0 = np.full(n, 0.5)
    f0 = float(np.sum(fun(x0) ** 2))
    pattern = np.stack([np.arange(n), np.arange(n)], axis=1)
    res = plateau_free.least_squares(fun, x0, budget=600, sigma0=0.2, sparsity=pattern, seed=4)
    assert res.fun < 1e-3 * f0, (res.fun, f0)


def test_pairs_and_a_mask_are_the_same_pattern():
    def fun(x):
        return np.array([x[0] * x[1] - 0.2, x[1] - 0.5, np.sin(x[2]) - 0.1])

    pairs = [(0, 0), (0, 1), (1, 1), (2, 2)]
    mask = np.zeros((3, 3), dtype=bool)
    for i, j in pairs:
        mask[i, j] = True
    a = plateau_free.least_squares(fun, [0.1, 0.1, 0.1], budget=200, sparsity=pairs, seed=5)
    b = plateau_free.least_squares(fun, [0.1, 0.1, 0.1], budget=200, sparsity=mask, seed=5)
    assert np.array_equal(a.x, b.x) and a.fun == b.fun
    assert a.fun < 1e-8


def test_same_bits_as_the_native_run_asked_and_told():
    def fun(x):
        return np.array([x[0] - 1.0, 2.0 * (x[1] + 0.5), x[0] * x[1] + 0.5])

    res = plateau_free.least_squares(fun, [0.0, 0.0], budget=150, sigma0=0.4, seed=9)
    raw = _native._LeastSquares([0.0, 0.0], 3, None, 150, 0.4, 8, 8, 1e-3, 1.0, "descent", False, None, 9)
    asked = 0
    while (ask := raw.ask()) is not None:
        points, seeds = ask
        assert points.dtype == np.float64 and seeds.dtype == np.uint64
        assert points.shape == (len(seeds), 2)
        asked += len(points)
        raw.tell(np.concatenate([fun(p) for p in points]).tolist())
    x, f, _, nit, _, nfev = raw.result()
    assert np.array_equal(res.x, x) and res.fun == f and res.nit == nit and res.nfev == nfev == asked
    assert asked <= 150


def test_every_point_lies_in_the_box():
    seen = []

    def fun(x):
        seen.append(x.copy())
        return x - np.array([2.0, -2.0])

    res = plateau_free.least_squares(fun, [0.5, 0.5], budget=100, sigma0=0.5, bounds=([0.0, 0.0], [1.0, 1.0]))
    pts = np.array(seen)
    assert (pts >= 0.0).all() and (pts <= 1.0).all()
    assert np.allclose(res.x, [1.0, 0.0])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"budget": 0}, "budget = 0"),
        ({"budget": 2.5}, "budget = 2.5"),
        ({"pairs": True}, "pairs = True"),
        ({"sigma0": 0.0}, "sigma0 = 0.0"),
        ({"sigma0": float("nan")}, "sigma0 = NaN is invalid"),
        ({"damping": -1.0}, "damping = -1.0"),
        ({"acceptance": "maybe"}, "acceptance = 'maybe'"),
        ({"sparsity": [(0, 5)]}, "sparsity parameter = 5"),
        ({"sparsity": [(0, -1)]}, "index -1 is negative"),
        ({"sparsity": np.ones((3, 3), dtype=bool)}, "shape"),
        ({"sparsity": "all"}, "sparsity must be"),
        ({"bounds": ([0.0, 0.0], [0.1, 0.1])}, r"x0\[0\] = 0.5 is outside bounds\[0\]"),
        ({"bounds": 3.0}, "bounds = 3.0 must be"),
        ({"seed": -1}, "seed = -1"),
        ({"on_failure": "skip"}, "on_failure = 'skip' is not a policy"),
        ({"workers": 0}, "workers = 0"),
        ({"disp": 1}, "disp = 1 must be True or False"),
        ({"callback": 3}, "callback = 3 must be callable"),
        ({"checkpoint": 3}, "checkpoint = 3 must be a path"),
        ({"checkpoint_every": -1}, "checkpoint_every = -1"),
        ({"keep_history": 0}, "keep_history = 0"),
        ({"smoothed_residuals": 1}, "smoothed_residuals = 1 must be True or False"),
    ],
)
def test_bad_options_are_value_errors_naming_them(kwargs, match):
    with pytest.raises(ValueError, match=match):
        plateau_free.least_squares(lambda x: x, [0.5, 0.5], **kwargs)


def test_bad_outputs_are_value_errors():
    with pytest.raises(ValueError, match="(?i)nan") as info:
        plateau_free.least_squares(lambda x: np.array([np.nan, 0.0]), [0.5, 0.5], on_failure="raise")
    assert info.value.result.status == 3 and info.value.result.nfev == 0  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match="empty"):
        plateau_free.least_squares(lambda x: np.array([]), [0.5, 0.5])
    calls = []

    def changing(x):
        calls.append(1)
        return np.zeros(2 if len(calls) == 1 else 3) + x[0]

    with pytest.raises(ValueError, match="must not change"):
        plateau_free.least_squares(changing, [0.5, 0.5])
    with pytest.raises(ValueError, match="1-D"):
        plateau_free.least_squares(lambda x: x, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="finite"):
        plateau_free.least_squares(lambda x: x, [np.inf, 0.0])
