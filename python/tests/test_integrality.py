"""``integrality=``, scipy's convention for integer variables: every point handed to ``fun``
and ``result.x`` integer on the declared coordinates and inside the bounds, the ask-and-tell
run the same, and a bad value a ValueError naming it."""

import numpy as np
import pytest

import plateau_free


def mixed(x):
    # The integer optimum of coordinates 0 and 1 is (0, 2) (from 0.3 and 1.6); 2.2 is continuous.
    return float(np.sum((np.asarray(x) - [0.3, 1.6, 2.2]) ** 2))


def test_every_point_and_the_result_are_integer_on_the_declared_coordinates():
    seen = []

    def recorded(x):
        seen.append(np.array(x))
        return mixed(x)

    bounds = [(-4.5, 4.5), (-3.0, 3.0), (-5.0, 5.0)]
    result = plateau_free.minimize(recorded, [2.7, 0.4, 0.0], integrality=[1, 1, 0],
                                   bounds=bounds, budget=1500, seed=3)
    points = np.array(seen)
    assert len(points) == result.nfev
    assert np.array_equal(points[:, :2], np.round(points[:, :2]))
    assert np.all(points[:, 0] >= -4.0) and np.all(points[:, 0] <= 4.0)
    # The start, rounded, is evaluated first.
    assert points[0].tolist() == [3.0, 0.0, 0.0]
    assert result.x[:2].tolist() == [0.0, 2.0]
    assert abs(result.x[2] - 2.2) < 1e-4
    assert result.fun == pytest.approx(0.09 + 0.16, abs=1e-8)


def test_ask_tell_asks_for_the_points_minimize_evaluates():
    options = dict(integrality=[True, False, True], budget=400, seed=5)
    run = plateau_free.ask_tell([1.2, 0.0, -0.7], **options)
    while not run.done:
        points, _ = run.ask()
        assert np.array_equal(points[:, [0, 2]], np.round(points[:, [0, 2]]))
        run.tell([mixed(x) for x in points])
    result = plateau_free.minimize(mixed, [1.2, 0.0, -0.7], **options)
    assert run.result.x.tolist() == result.x.tolist()


@pytest.mark.parametrize(
    "integrality, message",
    [
        ([1, 2, 0], "must be 0 or 1"),
        ([0.5, 0, 0], "must be 0 or 1"),
        ([1, 0], "has 2 entries, x0 has 3 coordinates"),
        ([[1, 0, 1]], "must be 0 or 1"),
        ("yes", "must be 0 or 1"),
    ],
)
def test_a_bad_integrality_is_a_value_error(integrality, message):
    with pytest.raises(ValueError, match=message):
        plateau_free.minimize(mixed, [0.0, 0.0, 0.0], integrality=integrality)


def test_bounds_without_an_integer_and_other_methods_are_refused():
    with pytest.raises(ValueError, match="no grid point"):
        plateau_free.minimize(mixed, [0.5, 0.0, 0.0], integrality=1,
                              bounds=[(0.2, 0.8), (-1, 1), (-1, 1)])
    with pytest.raises(ValueError, match="integrality"):
        plateau_free.minimize(mixed, [0.0, 0.0, 0.0], integrality=1, method="plateau")
    # One flag for all coordinates, as scipy allows.
    result = plateau_free.minimize(mixed, [0.0, 0.0, 0.0], integrality=1, budget=600)
    assert result.x.tolist() == [0.0, 2.0, 2.0]
