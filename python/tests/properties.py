"""What the property-based tests (``test_properties_*.py``) share: their Hypothesis settings,
the strategies drawing inputs of every shape, dtype and size, the check of a result or an
expected error, and the objectives.

The contract, for ``PlateauFreeGradient``, ``FiniteDifference`` and ``Spsa`` (``.estimate``),
``minimize`` (every method), ``ask_tell`` (ask, tell, result), ``Annealer`` and ``Adam``:
either a valid result -- finite float64 numbers, shaped as given -- or a ValueError or
TypeError with a message (``OptionTypeError`` is both), or the objective's own exception,
unchanged. Never a panic (``pyo3_runtime.PanicException``), a crashed interpreter, a hang or a
silent non-finite result; and inputs that are plainly valid give a result.

Deterministic: ``derandomize=True`` and no example database. A complex number is refused or
(numpy's casts) at least warned about; the properties run with numpy's ComplexWarning as an
error, so that no complex value passes silently.
"""

import math

import numpy as np
import pytest

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import plateau_free
from plateau_free import OptionTypeError

EXPECTED = (ValueError, TypeError)
HUGE_INT = 10**400  # no float holds it


def props(examples):
    """The settings of every property: deterministic, no database, no deadline."""
    return settings(
        max_examples=examples,
        derandomize=True,
        database=None,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large],
    )


# No complex value passes silently: numpy's casts warn, and the warning is an error here.
no_silent_complex = pytest.mark.filterwarnings("error::numpy.exceptions.ComplexWarning")


class Boom(Exception):
    """The objective's own exception: it must come out unchanged."""


def attempt(call):
    """``(result, None)`` or ``(None, exception)`` for an expected exception with a message.
    Anything else -- a PanicException, an OverflowError, a ZeroDivisionError -- propagates and
    fails the property."""
    try:
        return call(), None
    except EXPECTED as e:
        assert str(e).strip(), f"{type(e).__name__} without a message"
        return None, e


def assert_finite(array, shape):
    assert isinstance(array, np.ndarray), type(array)
    assert array.dtype == np.float64, array.dtype
    assert array.shape == tuple(shape), (array.shape, shape)
    assert np.all(np.isfinite(array)), array


# ---------------------------------------------------------------------------------------------
# Strategies

SHAPES = hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=3)
REAL_DTYPES = ["float16", "float32", "float64", "int8", "int16", "int32", "int64", "uint8", "uint16",
               "uint32", "uint64", "bool"]  # fmt: skip
ODD_FLOATS = [0.0, -0.0, 5e-324, 1e-300, 1e-12, 1e300, 1.7976931348623157e308, -1e300, math.nan,
              math.inf, -math.inf]  # fmt: skip


def real_arrays(shapes=SHAPES):
    return st.sampled_from(REAL_DTYPES).flatmap(lambda d: hnp.arrays(np.dtype(d), shapes))


def any_arrays():
    """Arrays, and things that are not arrays of numbers, of any shape, dtype and value."""
    complexes = st.sampled_from(["complex64", "complex128"]).flatmap(lambda d: hnp.arrays(np.dtype(d), SHAPES))
    words = st.one_of(st.sampled_from(["1", "-2.5", "nan", "inf", "x", ""]), st.text(max_size=4))
    strings = hnp.arrays(np.dtype("U6"), SHAPES, elements=words)
    elements = st.one_of(
        st.floats(), st.integers(), st.sampled_from([HUGE_INT, -HUGE_INT, 2**64]), st.none(), words,
        st.complex_numbers(), st.booleans(),
    )  # fmt: skip
    objects = hnp.arrays(object, SHAPES, elements=elements)
    ragged = st.lists(st.one_of(st.floats(), st.lists(st.floats(), max_size=2)), max_size=3)
    scalars = st.one_of(elements, st.sampled_from(ODD_FLOATS), st.just(b"12"), st.just({1: 2}))
    return st.one_of(real_arrays(), real_arrays(), complexes, strings, objects, ragged, scalars)


def plain(x):
    """Whether ``x`` is plainly valid (a non-empty array of moderate real numbers, which must
    give a result), plainly invalid (empty, non-finite or complex, which must raise) or
    neither (None)."""
    try:
        array = np.asarray(x)
    except Exception:
        return None
    if array.dtype.kind == "c":
        return False
    if array.dtype.kind not in "biuf":
        return None
    with np.errstate(all="ignore"):
        values = array.astype(np.float64)
    if values.size == 0 or not np.all(np.isfinite(values)):
        return False
    return bool(np.all(np.abs(values) <= 1e6)) or None


def spreads():
    """Spreads of every size and kind: scalars of every type and value, per-coordinate arrays."""
    floats = st.one_of(st.sampled_from(ODD_FLOATS), st.floats(), st.floats(1e-6, 1e6))
    return st.one_of(
        floats, floats, floats.map(np.float32), floats.map(np.float64), st.integers(-3, 10),
        st.sampled_from([HUGE_INT, True, None, "0.1", 1j, np.complex128(0.5)]),
        real_arrays(hnp.array_shapes(min_dims=0, max_dims=2, max_side=4)),
        st.lists(floats, max_size=4),
    )  # fmt: skip


def plain_spread(sigma, kind, x):
    """As :func:`plain`, for ``estimate``'s ``sigma`` (FiniteDifference ignores its value)."""
    if kind == "fd" or isinstance(sigma, (bool, np.bool_)):
        return None
    if isinstance(sigma, (int, float, np.floating)):
        try:
            value = float(sigma)
        except OverflowError:
            value = math.inf
        if not (math.isfinite(value) and value > 0):
            return False
        return (1e-6 <= value <= 1e6) or None
    if kind == "plateau" and isinstance(sigma, np.ndarray) and sigma.dtype.kind == "f":
        if sigma.size == np.size(x) and sigma.ndim == 1 and np.all((sigma >= 1e-6) & (sigma <= 1e6)):
            return True
    return None


def whole_numbers(low=-3, high=64, huge=True):
    """Integers of any size, as Python ints, numpy ints, whole and fractional floats, and
    things that are not integers."""
    small = st.integers(low, high)
    big = st.one_of(st.integers(2**45, 2**70), st.sampled_from([2**63 - 1, 2**63, 2**64 - 1, 2**64, -(2**63)]))
    odd = [2.5, math.nan, math.inf, True, False, None, "3", 3j] + ([1e300, HUGE_INT] if huge else [])
    return st.one_of(
        st.one_of(small, small, big) if huge else small,
        small.map(np.int64),
        (st.integers(0, 2**64 - 1) if huge else st.integers(max(low, 0), high)).map(np.uint64),
        small.map(float),
        st.sampled_from(odd),
    )


def seeds():
    return st.one_of(st.integers(0, 2**64 - 1), whole_numbers(-5, 2**20))


def smooth(x):
    """Finite at every finite point, of any shape."""
    return float(np.sum(np.sin(x)))


def smooth_batch(X):
    return np.sin(X).reshape(len(X), -1).sum(axis=1)


def objective(batched, seeded):
    if batched:
        return (lambda X, s: smooth_batch(X)) if seeded else smooth_batch
    return (lambda x, s: smooth(x)) if seeded else smooth


def stairs(x):
    return float(np.sum((np.floor(np.asarray(x) + 0.5) - 1.0) ** 2))

