"""Property-based tests (Hypothesis) of what the public entry points take: arrays of any shape
and dtype (floats of every width, ints, bools, complex numbers, objects, strings; NaN and
infinities; empty and 0-d arrays), spreads from 5e-324 to 1e300 (and 0, negative, NaN,
infinite), seeds, budgets and counts of any integer size and type, objectives that raise or
return what is not a number, and ask/tell sequences in any order.

The contract, for ``PlateauFreeGradient``, ``FiniteDifference`` and ``Spsa`` (``.estimate``),
``minimize`` (every method), ``ask_tell`` (ask, tell, result), ``Annealer`` and ``Adam``:
either a valid result -- finite float64 numbers, shaped as given -- or a ValueError or
TypeError with a message (``OptionTypeError`` is both), or the objective's own exception,
unchanged. Never a panic (``pyo3_runtime.PanicException``), a crashed interpreter, a hang or a
silent non-finite result; and inputs that are plainly valid give a result.

Deterministic: ``derandomize=True`` and no example database. A complex number is refused or
(numpy's casts) at least warned about; the properties run with numpy's ComplexWarning as an
error, so that no complex value passes silently. The bugs these properties found are the plain
regression tests at the end of the file.
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
# Hypothesis draws float16 values through a cast that may overflow (to the infinity it means).
pytestmark = pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning")


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


# ---------------------------------------------------------------------------------------------
# The estimators


@st.composite
def estimators(draw):
    """``(kind, make)``: an estimator's name and a function making it, with any options."""
    kind = draw(st.sampled_from(["plateau", "fd", "spsa"]))
    batched, seeded = draw(st.booleans()), draw(st.booleans())
    fun = objective(batched, seeded)
    seed = draw(st.integers(0, 2**64 - 1))
    if kind == "plateau":
        samples = draw(st.integers(1, 9))
        options = dict(
            samples=samples,
            sampling=draw(st.sampled_from(["radial", "per_coordinate", "gaussian", plateau_free.Sampling.Radial])),
            antithetic=draw(st.booleans()),
            orthogonal=draw(st.booleans()),
            parallel=draw(st.booleans()),
        )
        return kind, lambda: plateau_free.PlateauFreeGradient(fun, seed=seed, batched=batched, seeded=seeded, **options)
    if kind == "fd":
        step = draw(st.one_of(st.sampled_from(ODD_FLOATS), st.floats(1e-8, 1.0)))
        return kind, lambda: plateau_free.FiniteDifference(fun, step=step, seed=seed, batched=batched, seeded=seeded)
    return kind, lambda: plateau_free.Spsa(fun, seed=seed, batched=batched, seeded=seeded)


@no_silent_complex
@props(1000)
@given(estimators(), any_arrays(), spreads())
def test_estimate_is_finite_and_shaped_like_x_or_an_error(estimator, x, sigma):
    kind, make = estimator
    made, error = attempt(make)
    if error is not None:
        return  # a refused option (odd samples with pairs, a bad step...)
    gradient, error = attempt(lambda: made.estimate(x, sigma))
    valid_x, valid_sigma = plain(x), plain_spread(sigma, kind, x)
    if valid_x is False or valid_sigma is False:
        assert error is not None, f"estimate({x!r}, {sigma!r}) = {gradient!r}: not refused"
    elif valid_x and (valid_sigma or kind == "fd") and 1e-8 <= getattr(made, "step", 1.0) <= 1e6:
        assert error is None, f"estimate({x!r}, {sigma!r}) refused: {error!r}"
    if error is None:
        assert_finite(gradient, np.shape(x))


@props(400)
@given(
    st.sampled_from(["plateau", "fd", "spsa"]),
    real_arrays(hnp.array_shapes(min_dims=0, max_dims=2, min_side=1, max_side=3)),
    st.sampled_from(ODD_FLOATS + [1.0, 1e-6, 1e6]),
    st.sampled_from([1.0, 1e-300, 1e300, 1e308]),
)
def test_huge_and_tiny_spreads_and_values(kind, x, sigma, scale):
    # f of any size (up to 1e308 a unit): a finite gradient or a ValueError naming the overflow.
    def fun(p):
        return scale * smooth(p)

    make = {
        "plateau": lambda: plateau_free.PlateauFreeGradient(fun, samples=4),
        "fd": lambda: plateau_free.FiniteDifference(fun, step=sigma if math.isfinite(sigma) and sigma > 0 else 1e-3),
        "spsa": lambda: plateau_free.Spsa(fun),
    }[kind]
    gradient, error = attempt(lambda: make().estimate(x, sigma))
    if error is None:
        assert_finite(gradient, np.shape(x))
    else:
        assert isinstance(error, ValueError)


@props(600)
@given(
    samples=whole_numbers(),
    seed=seeds(),
    sampling=st.one_of(st.sampled_from(["radial", "Per-Coordinate", "gaussian", "spherical", "", None, 1]), st.text(max_size=3)),
    flags=st.lists(st.one_of(st.booleans(), st.sampled_from([np.True_, 0, 1, None, "yes"])), min_size=5, max_size=5),
)
def test_estimator_options_of_any_type_and_size(samples, seed, sampling, flags):
    antithetic, batched, seeded, orthogonal, parallel = flags
    fun = objective(batched is True or batched is np.True_, seeded is True or seeded is np.True_)
    made, error = attempt(
        lambda: plateau_free.PlateauFreeGradient(
            fun, samples=samples, sampling=sampling, antithetic=antithetic, seed=seed, batched=batched,
            seeded=seeded, orthogonal=orthogonal, parallel=parallel,
        )  # fmt: skip
    )
    if error is not None:
        return
    assert isinstance(made.samples, int) and made.samples >= 1 and 0 <= made.seed < 2**64
    # Every count runs or is refused: a count too large for memory is a ValueError, never an
    # abort (counts between 2**6 and 2**45 would run for long and are not tried).
    if made.samples <= 64 or made.samples >= 2**45:
        gradient, error = attempt(lambda: made.estimate([0.5, -0.25], 0.1))
        if error is None:
            assert_finite(gradient, (2,))
        else:
            assert made.samples <= 64 or "memory" in str(error)
    for est in (plateau_free.FiniteDifference, plateau_free.Spsa):
        other, error = attempt(lambda: est(fun, seed=seed, batched=batched, seeded=seeded))
        if error is None:
            assert_finite(other.estimate([0.5, -0.25], 0.1), (2,))


# ---------------------------------------------------------------------------------------------
# Objectives that misbehave

BAD_VALUES = [None, "1.0", b"1", 1j, np.complex128(1 + 1j), np.array([1.0, 2.0]), np.array([1.0]), [1.0],
              HUGE_INT, object(), {}, np.array(1 + 1j), math.nan, math.inf, -math.inf, Boom]  # fmt: skip
BAD_BATCHES = ["longer", "2-d", "none", "words", "complex", "objects", "nan", "inf", Boom]


def bad_batch(kind, n):
    return {
        "longer": lambda: np.zeros(n + 1),
        "2-d": lambda: np.zeros((n, 2)),
        "none": lambda: None,
        "words": lambda: ["a"] * n,
        "complex": lambda: np.full(n, 1 + 1j),
        "objects": lambda: [object()] * n,
        "nan": lambda: np.where(np.arange(n) == n - 1, np.nan, 0.0),
        "inf": lambda: np.full(n, -np.inf),
    }[kind]()


@no_silent_complex
@props(800)
@given(
    method=st.sampled_from(["adaptive", "plateau", "polished", "fd", "spsa"]),
    batched=st.booleans(),
    seeded=st.booleans(),
    bad=st.data(),
    at=st.integers(1, 40),
    x0=real_arrays(hnp.array_shapes(min_dims=0, max_dims=2, min_side=1, max_side=3)).filter(lambda a: plain(a) is True),
    seed=st.integers(0, 2**64 - 1),
)
def test_minimize_with_an_objective_that_raises_or_returns_non_numbers(method, batched, seeded, bad, at, x0, seed):
    """From its ``at``-th call on, ``fun`` returns something bad (or raises): the run ends in
    an exception of the right type (the objective's own exception unchanged), else it returns
    a valid result."""
    what = bad.draw(st.sampled_from(BAD_BATCHES if batched else BAD_VALUES))
    boom = Boom("from the objective")
    calls = [0]
    returned_bad = [False]

    def fun(x, *seeds):
        calls[0] += 1
        if calls[0] < at:
            return smooth_batch(x) if batched else smooth(x)
        returned_bad[0] = True
        if what is Boom:
            raise boom
        return bad_batch(what, len(x)) if batched else what

    options = dict(budget=40, seed=seed, batched=batched, seeded=seeded)
    if method in ("adaptive", "plateau", "polished"):
        options["on_failure"] = "raise"  # the baselines end on a failure anyway
    if method == "polished":
        options["polish"] = 0.5
    result, error = None, None
    try:
        result = plateau_free.minimize(fun, x0, method=method, **options)
    except Boom as e:
        assert e is boom and what is Boom and returned_bad[0]
        return
    except EXPECTED as e:
        error = e
        assert str(error).strip()
    if not returned_bad[0]:
        assert error is None, f"refused without a bad value: {error!r}"
        assert_finite(np.asarray(result.x), np.shape(x0))
        assert math.isfinite(result.fun) and result.nfev <= 40
        return
    assert error is not None, f"fun returned {what!r} and minimize returned {result!r}"
    if not batched and what is not None and isinstance(what, float):
        assert isinstance(error, ValueError) and not isinstance(error, TypeError)  # NaN, inf
    elif not batched:
        assert isinstance(error, TypeError), repr(error)  # not a number
    elif what in ("longer", "2-d", "nan", "inf"):
        assert isinstance(error, ValueError), repr(error)


@no_silent_complex
@props(100)
@given(st.sampled_from(BAD_VALUES), st.sampled_from(["plateau", "fd", "spsa"]), st.booleans())
def test_estimators_with_an_objective_that_misbehaves(what, kind, seeded):
    boom = Boom("raised by fun")

    def fun(x, *seed):
        if what is Boom:
            raise boom
        return what

    make = {"plateau": plateau_free.PlateauFreeGradient, "fd": plateau_free.FiniteDifference, "spsa": plateau_free.Spsa}
    estimator = make[kind](fun, seeded=seeded)
    with pytest.raises(Exception) as info:
        estimator.estimate([0.5, 1.5], 0.1)
    error = info.value
    if what is Boom:
        assert error is boom
    elif isinstance(what, float):
        assert isinstance(error, ValueError) and "returned" in str(error)
    else:
        assert isinstance(error, TypeError) and "fun must return a real number" in str(error)
    # The estimator stays usable after the error.
    assert estimator.nfev >= 1


# ---------------------------------------------------------------------------------------------
# minimize's options of any type and size


@no_silent_complex
@props(800)
@given(
    method=st.sampled_from(["adaptive", "plateau", "paper", "polished", "fd", "spsa", None]),
    x0=any_arrays(),
    budget=st.one_of(st.none(), whole_numbers(-2, 80)),
    seed=seeds(),
    extra=st.data(),
    stop_after=st.integers(1, 4),
)
def test_minimize_with_any_x0_budget_seed_and_counts(method, x0, budget, seed, extra, stop_after):
    chosen = {None: "adaptive", "paper": "plateau"}.get(method, method)
    options = {}
    if chosen in ("plateau", "polished"):
        options["samples"] = extra.draw(st.one_of(st.none(), whole_numbers(-2, 8)), label="samples")
    if chosen in ("plateau", "fd", "spsa"):
        options["iterations"] = extra.draw(st.one_of(st.none(), whole_numbers(-2, 6, huge=False)), label="iterations")
    if chosen in ("adaptive", "polished"):
        # Not of 2**40 and more within a budget as large: see the last regression test.
        options["population"] = extra.draw(st.one_of(st.none(), whole_numbers(-2, 12, huge=False)), label="population")
        options["sigma0"] = extra.draw(st.one_of(st.none(), spreads()), label="sigma0")
    if chosen == "polished":
        options["polish"] = extra.draw(st.sampled_from([None, 0.0, 0.5, 0.99, 1.0, -0.1, math.nan, "x", HUGE_INT]), label="polish")
    if chosen in ("plateau", "spsa"):
        options["sigma0"] = extra.draw(st.one_of(st.none(), spreads()), label="sigma0")
    calls = [0]

    def stop(x):  # every run ends within a few iterations, whatever the budget
        calls[0] += 1
        return calls[0] >= stop_after

    def run():
        return plateau_free.minimize(
            smooth, x0, method=method, budget=budget, seed=seed, callback=stop,
            **{k: v for k, v in options.items() if v is not None},
        )  # fmt: skip

    result, error = attempt(run)
    if plain(x0) is False:
        assert error is not None, f"x0 = {x0!r} not refused"
    if error is None:
        assert_finite(np.asarray(result.x), np.shape(x0))
        assert math.isfinite(result.fun)
        assert isinstance(result.nfev, int) and result.nfev >= 1
        if budget is not None:
            assert result.nfev <= int(budget)
        assert result.status in (0, 1, 99) and result.message


@props(400)
@given(
    method=st.sampled_from(["adaptive", "plateau", "polished", "fd", "spsa"]),
    bounds=st.one_of(
        st.tuples(st.sampled_from(ODD_FLOATS + [None, -1.0, 0.0, HUGE_INT, "0"]), st.sampled_from(ODD_FLOATS + [None, 1.0, 2.0, -HUGE_INT])),
        st.lists(st.tuples(st.sampled_from([None, -1.0, 0.0, 1e300]), st.sampled_from([None, 1.0, 2.0, 1e308])), min_size=0, max_size=3),
        st.sampled_from([None, "box", 3, [1, 2, 3], [(0, 1, 2)], [(1j, 2)], np.array([[0.0, 1.0]] * 2)]),
    ),
    target=st.one_of(st.none(), st.sampled_from(ODD_FLOATS + [HUGE_INT, "0", True])),
    lr=st.one_of(st.none(), st.sampled_from(ODD_FLOATS + [HUGE_INT, 0.01, "0.1"])),
)
def test_minimize_with_any_bounds_target_and_rate(method, bounds, target, lr):
    options = {}
    if target is not None and method in ("adaptive", "polished"):
        options["target"] = target
    if lr is not None and method in ("plateau", "polished", "fd", "spsa"):
        options["lr"] = lr
    x0 = [0.5, 0.5]
    result, error = attempt(
        lambda: plateau_free.minimize(smooth, x0, method=method, budget=30, bounds=bounds, **options)
    )
    if error is None:
        assert_finite(np.asarray(result.x), (2,))
        assert math.isfinite(result.fun) and result.nfev <= 30


# ---------------------------------------------------------------------------------------------
# ask and tell in any order


def stairs(x):
    return float(np.sum((np.floor(np.asarray(x) + 0.5) - 1.0) ** 2))


MISTAKES = ["ask again", "shorter", "longer", "nothing", "nan", "inf", "none", "words", "complex",
            "huge int", "result", "best", "nested"]  # fmt: skip


def make_run(method, x0, seed):
    """A run that refuses non-finite values (``on_failure='raise'``), to test the refusals."""
    if method == "plateau":
        return plateau_free.ask_tell(x0, method=method, iterations=6, seed=seed, on_failure="raise")
    return plateau_free.ask_tell(x0, method=method, budget=40, seed=seed, on_failure="raise")


def make_mistake(es, mistake, X):
    """One wrong call while ``X`` waits for its values: an error of the right type, which
    changes nothing."""
    k = len(X)
    good = [stairs(x) for x in X]
    told = {
        "shorter": good[:-1],
        "longer": good + [1.0],
        "nothing": [],
        "nan": good[:-1] + [math.nan],
        "inf": [math.inf] + good[1:],
        "none": None,
        "words": ["one"] * k,
        "complex": [1j] * k,
        "huge int": [HUGE_INT] * k,
        "nested": [[1.0, 2.0], [3.0]],
    }
    if mistake == "ask again":
        with pytest.raises(ValueError, match="ask called twice"):
            es.ask()
    elif mistake == "result":
        with pytest.raises(ValueError, match="not ended"):
            es.result
    elif mistake == "best":
        best = es.best
        if best is not None:
            assert_finite(best[0], X.shape[1:])
            assert math.isfinite(best[1])
    else:
        expected = TypeError if mistake in ("none", "words", "complex", "nested") else ValueError
        with pytest.raises(expected) as info:
            es.tell(told[mistake])
        assert str(info.value).strip()


@props(150)
@given(
    method=st.sampled_from(["adaptive", "plateau", "polished"]),
    x0=st.sampled_from([[0.3], [0.2, -0.4], np.zeros((2, 2)), np.array(0.7)]),
    seed=st.integers(0, 2**64 - 1),
    plan=st.lists(st.lists(st.sampled_from(MISTAKES), max_size=3), min_size=1, max_size=8),
)
def test_ask_tell_in_any_order_ends_as_the_clean_run(method, x0, seed, plan):
    """Wrong calls (asking twice, telling the wrong count, NaN, infinities, non-numbers, the
    result too early) between the right ones: each an error of the right type that changes
    nothing, and the run ends bit for bit as the run without them."""
    clean = make_run(method, x0, seed)
    while not clean.done:
        X, _ = clean.ask()
        clean.tell([stairs(x) for x in X])
    es = make_run(method, x0, seed)
    with pytest.raises(ValueError, match="tell without ask"):
        es.tell([1.0])
    step = 0
    while not es.done:
        X, seeds = es.ask()
        assert_finite(X, X.shape) and X.shape[1:] == np.shape(x0)
        assert seeds.dtype == np.uint64 and len(seeds) == len(X) >= 1
        for mistake in plan[step % len(plan)]:
            make_mistake(es, mistake, X)
        es.tell(np.array([stairs(x) for x in X]))
        if method != "plateau":
            assert es.nfev <= 40
        step += 1
    with pytest.raises(ValueError, match="has ended"):
        es.ask()
    with pytest.raises(ValueError, match="tell without ask"):
        es.tell([1.0])
    result, expected = es.result, clean.result
    np.testing.assert_array_equal(result.x, expected.x)
    assert result.x.shape == np.shape(x0) and np.all(np.isfinite(result.x))
    assert result.fun == expected.fun and math.isfinite(result.fun)
    assert result.nfev == expected.nfev and result.nit == expected.nit


@props(300)
@given(
    x0=any_arrays(),
    method=st.sampled_from(["adaptive", "plateau", "polished", "fd", "spsa", "newton", None, 3]),
    budget=st.one_of(st.none(), whole_numbers(-2, 50)),
    seed=seeds(),
)
def test_ask_tell_options_of_any_kind(x0, method, budget, seed):
    options = dict(iterations=3) if method == "plateau" and budget is None else {}
    es, error = attempt(lambda: plateau_free.ask_tell(x0, method=method, budget=budget, seed=seed, **options))
    if plain(x0) is False:
        assert error is not None
    if error is not None:
        return
    for _ in range(3):  # a few rounds: the points are finite and shaped like x0
        if es.done:
            break
        asked, error = attempt(es.ask)  # x0 near 1e308: the points overflow (a ValueError)
        if error is not None:
            return
        X, seeds = asked
        assert_finite(X, (len(seeds),) + np.shape(x0))
        es.tell([smooth(x) for x in X])


# ---------------------------------------------------------------------------------------------
# Annealer and Adam


@props(800)
@given(
    schedule=st.one_of(st.sampled_from(["paper", "constant", "exponential", "cosine", "Cosine", "linear", ""]), st.sampled_from([None, 1, b"paper"])),
    sigma0=st.one_of(st.sampled_from(ODD_FLOATS), st.floats(), st.sampled_from([HUGE_INT, "0.5", None, True])),
    sigma_min=st.one_of(st.sampled_from(ODD_FLOATS), st.floats()),
    iterations=whole_numbers(-2, 50),
    warmup=st.one_of(st.sampled_from([0.0, 0.5, 0.999, 1.0, -0.1, math.nan, math.inf]), st.floats(0, 1)),
    at=st.lists(st.one_of(st.integers(0, 2**64 - 1), st.integers(-3, 60), st.sampled_from([2**64, 1.5, "1", True])), max_size=4),
)
def test_annealer_of_any_schedule(schedule, sigma0, sigma_min, iterations, warmup, at):
    annealer, error = attempt(lambda: plateau_free.Annealer(schedule, sigma0, sigma_min, iterations, warmup))
    if error is not None:
        return
    assert annealer.iterations >= 1
    for i in at:
        sigma, error = attempt(lambda: annealer.sigma(i))
        if error is None:
            assert math.isfinite(sigma) and sigma > 0, (i, sigma)
    if annealer.iterations <= 10**5:  # sigmas() holds one float per iteration
        sigmas = annealer.sigmas()
        assert_finite(sigmas, (annealer.iterations,))
        assert np.all(sigmas > 0)
    for shortcut in (plateau_free.Annealer.paper, plateau_free.Annealer.constant):
        other, error = attempt(lambda: shortcut(sigma0, iterations))
        if error is None:
            assert math.isfinite(other.sigma(0)) and other.sigma(0) > 0


@no_silent_complex
@props(800)
@given(
    lr=st.one_of(st.sampled_from(ODD_FLOATS + [0.02, 1.0, 1e6]), st.sampled_from([HUGE_INT, "0.1", None])),
    betas=st.tuples(st.sampled_from([0.0, 0.9, 0.999999, 1.0, -0.5, math.nan]), st.sampled_from([0.0, 0.999, 1.0, math.nan])),
    epsilon=st.sampled_from([1e-8, 5e-324, 0.0, -1.0, 1e308, math.inf]),
    bounded=st.booleans(),
    x=any_arrays(),
    gradient=st.one_of(any_arrays(), st.just("same shape")),
    steps=st.integers(1, 3),
)
def test_adam_steps_with_any_input(lr, betas, epsilon, bounded, x, gradient, steps):
    n = max(int(np.size(x)) if plain(x) is not None else 1, 1)
    bounds = ([-1.0] * n, [1.0] * n) if bounded else None
    adam, error = attempt(lambda: plateau_free.Adam(lr, betas[0], betas[1], epsilon, bounds))
    if error is not None:
        return
    if isinstance(gradient, str):
        try:
            gradient = np.ones(np.shape(x))
        except ValueError:  # a ragged x has no shape; whatever the gradient, x is refused
            gradient = np.ones(1)
    current = x
    for _ in range(steps):
        stepped, error = attempt(lambda: adam.step(current, gradient))
        if plain(x) is False or plain(gradient) is False:
            assert error is not None, f"Adam.step({x!r}, {gradient!r}) not refused"
        if error is not None:
            return
        assert_finite(stepped, np.shape(x))
        if bounded:
            assert np.all((stepped >= -1.0) & (stepped <= 1.0))
        current = stepped


# ---------------------------------------------------------------------------------------------
# Regression tests: the bugs the properties found.


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_ask_tell_refuses_a_non_finite_final_value(bad):
    # The paper loop's final evaluation took any value: result.fun was NaN, silently
    # (minimize refuses it).
    es = plateau_free.ask_tell([0.25, 0.5], method="plateau", iterations=1)
    X, _ = es.ask()
    es.tell([stairs(x) for x in X])
    X, seeds = es.ask()
    assert len(X) == 1 and not es.done
    with pytest.raises(ValueError, match=r"at evaluation 2, point \[0\.\d*, 0\.\d*\]: tell finite values"):
        es.tell([bad])
    assert not es.done
    es.tell([3.0])
    assert es.done and es.result.fun == 3.0


@pytest.mark.parametrize(
    "values, error",
    [(None, TypeError), ([1j, 1.0], TypeError), (np.array([1 + 0j, 2 + 0j]), TypeError), ({1.0, 2.0}, TypeError),
     (["one", "two"], TypeError), ([HUGE_INT, 1.0], ValueError)],
)  # fmt: skip
def test_tell_of_non_numbers_is_a_clear_error(values, error):
    # tell(None) said "f returned NaN", a complex value was told by its real part (a
    # ComplexWarning aside), an int too large for a float was an OverflowError.
    es = plateau_free.ask_tell([0.0], method="plateau", iterations=2)
    X, _ = es.ask()
    with pytest.raises(error, match="must be real numbers, one per asked point"):
        es.tell(values)
    es.tell([1.0, 2.0])  # the same points still waited for their values


@pytest.mark.parametrize(
    "options",
    [dict(sigma0=HUGE_INT), dict(target=-HUGE_INT), dict(bounds=[(0, HUGE_INT)]),
     dict(method="plateau", lr=HUGE_INT), dict(method="plateau", sigma_min=HUGE_INT),
     dict(method="fd", step=HUGE_INT)],
)  # fmt: skip
def test_an_int_too_large_for_a_float_is_a_value_error(options):
    # An OverflowError (neither a ValueError nor a TypeError) before.
    with pytest.raises(ValueError, match="too large for a float"):
        plateau_free.minimize(smooth, [0.5], budget=30, **options)


def test_x0_with_an_int_too_large_for_a_float_is_a_value_error():
    with pytest.raises(ValueError, match="x0 = .* is not an array of finite numbers"):
        plateau_free.minimize(smooth, [0.5, HUGE_INT], budget=30)


@pytest.mark.parametrize("population, budget", [(2**62, None), (2**62, 100), (101, 100), (2**64 - 1, 2**40)])
def test_a_population_larger_than_the_budget_is_refused(population, budget):
    # A PanicException ("capacity overflow") or an aborted interpreter (a failed allocation)
    # before: the whole generation was drawn before the budget cut it.
    with pytest.raises(ValueError, match="population = .* is more than .*budget"):
        plateau_free.minimize(smooth, [0.5], population=population, budget=budget)
    with pytest.raises(ValueError, match="population = .* is more than .*budget"):
        plateau_free.ask_tell([0.5], population=population, budget=budget)
    assert plateau_free.minimize(smooth, [0.5], population=100, budget=100).nfev <= 100


@pytest.mark.parametrize(
    "final, error",
    [("1.0", TypeError), (b"1", TypeError), (np.complex128(1 + 0j), TypeError), (np.array([1.0]), TypeError)],
)  # fmt: skip
def test_the_final_evaluation_takes_what_the_loop_takes(final, error):
    # The paper loop's final evaluation (in Python) took a string as a number, and a complex
    # number by its real part; the loop's evaluations (in Rust) refuse both.
    calls = [0]

    def fun(x):
        calls[0] += 1
        return final if calls[0] == 2 * 3 + 1 else smooth(x)

    with pytest.raises(error, match="fun must return a real number"):
        plateau_free.minimize(fun, [0.5], method="plateau", iterations=3)


@pytest.mark.parametrize(
    "final, error, text",
    [(lambda X: np.zeros(3), ValueError, "must return 1 value"), (lambda X: ["1.5"], TypeError, "1 real number"),
     (lambda X: np.array([2 + 0j]), TypeError, "1 real number"), (lambda X: None, TypeError, "1 real number")],
)  # fmt: skip
def test_the_final_batched_evaluation_checks_the_batch(final, error, text):
    # It took the first of any number of values, and strings and complex numbers as numbers.
    calls = [0]

    def fun(X):
        calls[0] += 1
        return final(X) if calls[0] == 4 else smooth_batch(X)

    with pytest.raises(error, match=text):
        plateau_free.minimize(fun, [0.5], method="plateau", iterations=3, batched=True)


# Found by the properties above, fixed in the Rust extension (python/src) or the library (src/).


def test_annealer_sigmas_of_a_huge_schedule_is_an_error_not_a_panic():
    # PanicException: capacity overflow (and a failed allocation, aborting the interpreter,
    # for 2**40 iterations).
    with pytest.raises((ValueError, MemoryError), match="iterations"):
        plateau_free.Annealer("cosine", iterations=2**62).sigmas()


@pytest.mark.filterwarnings("ignore::numpy.exceptions.ComplexWarning")
def test_complex_x_sigma_and_gradient_are_refused():
    grad = plateau_free.PlateauFreeGradient(smooth)
    with pytest.raises(OptionTypeError, match="x = "):
        grad.estimate(np.array([0.5 + 1j]), 0.1)
    with pytest.raises(OptionTypeError, match="sigma = "):
        grad.estimate([0.5], np.array([0.1 + 1j]))
    with pytest.raises(OptionTypeError, match="gradient = "):
        plateau_free.Adam().step([0.5], np.array([1 + 1j]))


@pytest.mark.filterwarnings("ignore::numpy.exceptions.ComplexWarning")
def test_a_batched_fun_returning_complex_numbers_is_refused():
    with pytest.raises(TypeError, match="batched fun must return"):
        plateau_free.minimize(lambda X: np.full(len(X), 1 + 1j), [0.5], budget=20, batched=True)


@pytest.mark.filterwarnings("ignore::numpy.exceptions.ComplexWarning")
@pytest.mark.parametrize("value", [np.complex128(1 + 1j), np.complex64(2 + 0j)])
def test_fun_returning_a_numpy_complex_number_is_refused(value):
    # Python's complex is refused (TypeError); numpy's was taken by its real part.
    with pytest.raises(TypeError, match="fun must return a real number"):
        plateau_free.PlateauFreeGradient(lambda x: value).estimate([0.5], 0.1)


def test_a_population_too_large_for_memory_is_an_error_not_a_panic():
    # Within a (huge) budget: PanicException "capacity overflow" (and an aborted interpreter
    # for populations of 2**40 and so).
    with pytest.raises(ValueError, match="population"):
        plateau_free.minimize(smooth, [0.5], population=2**62, budget=2**63)
