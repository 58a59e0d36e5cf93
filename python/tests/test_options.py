"""One default method, chosen by ``method=`` alone, and every bad option a ValueError
that names the option and shows its value as written."""

import math
import re

import numpy as np
import pytest

import plateau_free
from helpers import staircase

X0 = [0.0, 0.0, 0.0]


def test_minimize_with_nothing_else_runs_the_adaptive_search_at_its_default_budget():
    # minimize(f, x0) with no method runs the adaptive search at its default budget (1000
    # evaluations per coordinate), which reaches 0 on a 50-D staircase.
    calls = [0]

    def counted(x):
        calls[0] += 1
        return staircase(x)

    result = plateau_free.minimize(counted, np.zeros(50))
    assert "restarts" in result and isinstance(result.history, plateau_free.SearchHistory)
    assert calls[0] == result.nfev <= 1000 * 50
    assert result.fun == 0.0
    assert result.message.startswith(("target reached", "done")) or "of at most 50000 evaluations" in result.message
    assert plateau_free.ask_tell(X0).method == "adaptive"
    assert plateau_free.minimize(staircase, X0, method=None).nfev == plateau_free.minimize(staircase, X0).nfev


# A value of every option, to give to the methods that do not take it.
VALUES = dict(
    budget=100, sigma0=0.5, bounds=[(-5, 5)] * 3, callback=print, target=0.0, population=6,
    restarts=False, polish=0.2, iterations=10, lr=0.1, samples=4, sampling="gaussian",
    antithetic=False, annealer="cosine", sigma_min=0.05, step=0.01, orthogonal=True,
    parallel=True, record_x=True, final_evaluation=False, checkpoint="never-written.json",
    checkpoint_every=3, keep_history=5, stop_when_stalled=0.2, workers=2, disp=False,
    patience=2, args=(1,), on_failure="raise", metric="diagonal",
)  # fmt: skip
# Options that every method takes.
EVERY = {"budget", "bounds", "callback", "checkpoint", "checkpoint_every", "keep_history", "args",
         "workers", "disp"}
TAKES = {
    "adaptive": EVERY | {"sigma0", "target", "population", "restarts", "stop_when_stalled",
                         "workers", "disp", "patience", "on_failure", "metric"},
    "polished": EVERY | {"sigma0", "target", "population", "restarts", "polish", "lr", "samples",
                         "stop_when_stalled", "workers", "disp", "patience", "on_failure",
                         "metric"},
    "plateau": EVERY | {"sigma0", "iterations", "lr", "samples", "sampling", "antithetic",
                        "annealer", "sigma_min", "orthogonal", "parallel", "record_x",
                        "final_evaluation", "workers", "disp", "on_failure"},
    "spsa": EVERY | {"sigma0", "iterations", "lr", "annealer", "sigma_min", "record_x",
                     "final_evaluation"},
    "fd": EVERY | {"iterations", "lr", "step", "record_x", "final_evaluation"},
}  # fmt: skip


FOREIGN = [
    (method, name)
    for method in [None, "adaptive", "polished", "plateau", "paper", "spsa", "fd"]
    for name in sorted(VALUES)
    if name not in TAKES[{None: "adaptive", "paper": "plateau"}.get(method, method)]
]


@pytest.mark.parametrize("method, name", FOREIGN)
def test_an_option_of_another_method_is_a_value_error_naming_it(method, name):
    canonical = {None: "adaptive", "paper": "plateau"}.get(method, method)
    # An option of another method is an error: it never silently switches the method.
    value = VALUES[name]
    named = re.escape(f"{name} = {value!r}: not an option of method='{canonical}'")
    options = {"budget": 100, name: value}
    with pytest.raises(ValueError, match=named):
        plateau_free.minimize(staircase, X0, method=method, **options)
    if canonical in ("adaptive", "polished", "plateau") and name not in (
        "callback", "parallel", "checkpoint", "checkpoint_every", "step", "workers", "disp",
        "args",  # minimize's alone
    ):
        with pytest.raises(ValueError, match=named):
            plateau_free.ask_tell(X0, method=method, **options)


@pytest.mark.parametrize("method", ["adaptive", "polished", "plateau", "spsa", "fd"])
def test_every_option_a_method_takes_is_accepted(method):
    options = {
        name: VALUES[name] for name in TAKES[method] if name not in ("checkpoint", "callback", "args")
    }
    if method == "plateau":
        options.update(antithetic=True, orthogonal=False, sampling="radial")  # a valid combination
    if method == "polished":
        options.update(samples=2, polish=0.25)
    options.pop("budget" if "iterations" in options else "", None)
    result = plateau_free.minimize(staircase, X0, method=method, **options)
    assert result.nfev >= 1


# (options, the text the error must hold): every option, every wrong type; the value as written.
BAD = [
    (dict(seed=-1), "seed = -1 must be a whole number from 0 to 2**64 - 1"),
    (dict(seed=1.5), "seed = 1.5 must be a whole number"),
    (dict(seed=2**64), "seed = 18446744073709551616 must be a whole number"),
    (dict(seed="7"), "seed = '7' must be a whole number"),
    (dict(seed=True), "seed = True must be a whole number"),
    (dict(budget=10**30), "budget = 1000000000000000000000000000000 must be a whole number of evaluations, not negative and at most 18446744073709551615"),
    (dict(budget=np.nan), "budget = nan must be a whole number of evaluations"),
    (dict(budget=math.inf), "budget = inf must be a whole number of evaluations"),
    (dict(budget=1.5), "budget = 1.5 must be a whole number of evaluations"),
    (dict(budget="a"), "budget = 'a' must be a whole number of evaluations"),
    (dict(budget=True), "budget = True must be a whole number of evaluations"),
    (dict(budget=0), "budget = 0 is invalid: must be at least 1 evaluation"),
    (dict(budget=np.int64(-3)), "budget = -3 must be a whole number of evaluations, not negative and at most 18446744073709551615"),
    (dict(bounds=[(1, 2, 3)] * 3), "bounds[0] = (1, 2, 3) must be a (lower, upper) pair of numbers or None"),
    (dict(bounds=[(0, "a")] * 3), "bounds[0] = (0, 'a') must be a (lower, upper) pair"),
    (dict(bounds=5), "bounds = 5 must be (lower, upper) pairs"),
    (dict(bounds=[(-1, 1)] * 2), "bounds has 2 (lower, upper) pairs, x0 has 3 coordinates"),
    (dict(bounds=[(-1, 1), (1, -1), (-1, 1)]), "bounds[1] = (1, -1): lower 1 > upper -1"),
    (dict(bounds=[(-1, 1), (-1, math.nan), (-1, 1)]), "bounds[1] = (-1, nan): NaN is not a bound"),
    (dict(sigma0="a"), "sigma0 = 'a' must be a number"),
    (dict(sigma0=0), "sigma0 = 0.0 is invalid: must be finite and > 0"),
    (dict(sigma0=-1), "sigma0 = -1.0 is invalid: must be finite and > 0"),
    (dict(sigma0=np.float64(np.inf)), "sigma0 = inf is invalid: must be finite and > 0"),
    (dict(target="low"), "target = 'low' must be a number"),
    (dict(target=math.nan), "target = NaN is invalid: must not be NaN"),
    (dict(population=1), "population = 1 is invalid: must be at least 2"),
    (dict(population=4.5), "population = 4.5 must be a whole number, not negative and at most 18446744073709551615"),
    (dict(restarts="yes"), "restarts = 'yes' must be True or False"),
    (dict(metric="sparse"), "metric = 'sparse' is not a metric: use 'auto', 'full', 'decoded', 'diagonal' or 'low_rank'"),
    (dict(metric=2), "metric = 2 is not a metric"),
    (dict(on_failure="ignore"), "on_failure = 'ignore' is not a policy: use 'continue' or 'raise'"),
    (dict(on_failure=True), "on_failure = True is not a policy"),
    (dict(workers=0), "workers = 0 must be a whole number of threads from 1"),
    (dict(workers="many"), "workers = 'many' must be a number of threads"),
    (dict(batched=True, workers=2), "workers = 2: a batched fun evaluates its batch itself"),
    (dict(sigma0=[1.0, 0.0, 1.0]), "sigma0 = 0.0 is invalid: must be finite and > 0 (every coordinate's spread)"),
    (dict(sigma0=[1.0, 1.0]), "sigma0 has 2 spreads, x0 has 3 coordinates"),
    (dict(method="plateau", sigma0=[1.0, 1.0, 1.0]), "method='plateau' takes one number"),
    (dict(patience=-1), "patience = -1 must be a whole number of restarts, not negative and at most 18446744073709551615"),
    (dict(restarts=1), "restarts = 1 must be True or False"),
    (dict(batched=1), "batched = 1 must be True or False"),
    (dict(seeded=None), "seeded = None must be True or False"),
    (dict(callback=5), "callback = 5 must be callable"),
    (dict(method=3), "method = 3 is not a method: use 'adaptive', 'plateau', 'polished', 'fd' or 'spsa'"),
    (dict(method="newton"), "method = 'newton' is not a method of minimize"),
    (dict(method="polished", budget=100, polish=1), "polish = 1.0 is invalid: must be a fraction of the budget in [0, 1): the share"),
    (dict(method="polished", budget=100, polish="a"), "polish = 'a' must be a number"),
    (dict(stop_when_stalled=0), "stop_when_stalled = 0.0 is invalid: must be a fraction of the budget in (0, 1]: the window"),
    (dict(stop_when_stalled=-0.2), "stop_when_stalled = -0.2 is invalid: must be a fraction of the budget in (0, 1]"),
    (dict(stop_when_stalled=1.5), "stop_when_stalled = 1.5 is invalid: must be a fraction of the budget in (0, 1]"),
    (dict(stop_when_stalled=math.nan), "stop_when_stalled = NaN is invalid: must be a fraction of the budget"),
    (dict(stop_when_stalled=math.inf), "stop_when_stalled = inf is invalid: must be a fraction of the budget"),
    (dict(stop_when_stalled="0.2"), "stop_when_stalled = '0.2' must be a number"),
    (dict(stop_when_stalled=True), "stop_when_stalled = True must be a number"),
    (dict(method="polished", budget=100, stop_when_stalled=np.float64(2.0)),
     "stop_when_stalled = 2.0 is invalid: must be a fraction of the budget in (0, 1]"),
    (dict(method="polished", budget=100, samples=3), "samples = 3: antithetic pairs need an even number"),
    (dict(method="plateau", iterations=0), "iterations = 0 must be a whole number from 1"),
    (dict(method="plateau", iterations=2.5), "iterations = 2.5 must be a whole number from 1"),
    (dict(method="plateau", lr="fast"), "lr = 'fast' must be a number"),
    (dict(method="plateau", lr=0), "lr = 0.0 is invalid: must be finite and > 0"),
    (dict(method="plateau", samples=0), "samples = 0 must be a whole number from 1"),
    (dict(method="plateau", samples="2"), "samples = '2' must be a whole number, not negative"),
    (dict(method="plateau", samples=5), "samples = 5: antithetic pairs need an even number of samples"),
    (dict(method="plateau", sampling="spherical"), "sampling = 'spherical' is not a sampler"),
    (dict(method="plateau", sampling=2), "sampling = 2 is not a sampler"),
    (dict(method="plateau", antithetic="no"), "antithetic = 'no' must be True or False"),
    (dict(method="plateau", orthogonal=0), "orthogonal = 0 must be True or False"),
    (dict(method="plateau", parallel=None, record_x="x"), "record_x = 'x' must be True or False"),
    (dict(method="plateau", final_evaluation=1), "final_evaluation = 1 must be True or False"),
    (dict(method="plateau", annealer="linear"), "annealer = 'linear' is not a schedule"),
    (dict(method="plateau", annealer=0.5), "annealer = 0.5 is not a schedule"),
    (dict(method="plateau", sigma_min=-0.1), "sigma_min = -0.1 is invalid: must be finite and > 0"),
    (dict(method="plateau", annealer=plateau_free.Annealer.cosine(0.3, 0.02, 25), sigma0=0.4),
     "sigma0 = 0.4: the Annealer given as annealer has its own (0.3)"),
    (dict(method="fd", step=0), "step = 0.0 is invalid: must be finite and > 0"),
    (dict(method="plateau", checkpoint=5), "checkpoint = 5 must be a path"),
    (dict(method="plateau", keep_history=0), "keep_history = 0 must be a whole number of iterations from 1"),
    (dict(method="plateau", checkpoint="c.json", checkpoint_every=-1), "checkpoint_every = -1 must be a whole number of iterations from 0"),
    (dict(method="plateau", checkpoint="c.json", checkpoint_every=1.5), "checkpoint_every = 1.5 must be a whole number"),
    (dict(x0=None), "x0 = None must be an array of numbers"),
    (dict(x0="abc"), "x0 = 'abc' must be an array of numbers"),
    (dict(x0=[[1.0, 2.0], [3.0]]), "x0 = [[1.0, 2.0], [3.0]] is not an array of numbers: "),
    (dict(x0=[1.0, "a", 3.0]), "x0 = [1.0, 'a', 3.0] is not an array of numbers"),
    (dict(x0=[1j, 0.0, 0.0]), "x0 = [1j, 0.0, 0.0] is not an array of numbers"),
    (dict(x0=[]), "x0 = [] is empty"),
    (dict(x0=[0.0, None, 0.0]), "x0[1] = None is not finite"),
    (dict(x0=[[0.0, 1.0], [math.inf, 0.0]]), "x0[1, 0] = inf is not finite"),
    (dict(fun=42), "fun = 42 must be callable"),
]


@pytest.mark.parametrize("options, text", BAD, ids=[t for _, t in BAD])
def test_errors_name_the_option_and_show_the_value(tmp_path, monkeypatch, options, text):
    monkeypatch.chdir(tmp_path)
    options = dict(options)
    fun = options.pop("fun", staircase)
    x0 = options.pop("x0", X0)
    with pytest.raises(ValueError) as info:
        plateau_free.minimize(fun, x0, **options)
    assert text in str(info.value)
    assert "1e0" not in str(info.value)
    if isinstance(info.value, TypeError):  # a wrong type: both, as scipy users may catch either
        assert isinstance(info.value, plateau_free.OptionTypeError)
    assert list(tmp_path.iterdir()) == []  # no checkpoint written


@pytest.mark.parametrize(
    "options, text",
    [
        (dict(seed="1"), "seed = '1' must be a whole number"),
        (dict(budget="a"), "budget = 'a' must be a whole number"),
        (dict(x0=None), "x0 = None must be an array of numbers"),
        (dict(method="fd"), "method = 'fd' is not a method of ask_tell"),
        (dict(method="plateau", lr=-1), "lr = -1.0 is invalid: must be finite and > 0"),
        (dict(stop_when_stalled=0), "stop_when_stalled = 0.0 is invalid: must be a fraction of the budget in (0, 1]: the window"),
        (dict(bounds=[(1, 2, 3)] * 3), "bounds[0] = (1, 2, 3) must be a (lower, upper) pair"),
    ],
)
def test_ask_tell_errors_name_the_option_and_show_the_value(options, text):
    options = dict(options)
    x0 = options.pop("x0", X0)
    with pytest.raises(ValueError, match=re.escape(text)):
        plateau_free.ask_tell(x0, **options)


@pytest.mark.parametrize(
    "make, text",
    [
        (lambda: plateau_free.PlateauFreeGradient(staircase, seed=None), "seed = None must be a whole number from 0"),
        (lambda: plateau_free.PlateauFreeGradient(staircase, seed=2**64), "seed = 18446744073709551616 must be"),
        (lambda: plateau_free.PlateauFreeGradient(staircase, samples=1.5), "samples = 1.5 must be a whole number from 1"),
        (lambda: plateau_free.PlateauFreeGradient(staircase, sampling=None), "sampling = None must be a name"),
        (lambda: plateau_free.PlateauFreeGradient(staircase, antithetic="yes"), "antithetic = 'yes' must be True or False"),
        (lambda: plateau_free.PlateauFreeGradient(staircase, batched=1), "batched = 1 must be True or False"),
        (lambda: plateau_free.FiniteDifference(staircase, step="small"), "step = 'small' must be a number"),
        (lambda: plateau_free.Spsa(staircase, seed=-2), "seed = -2 must be a whole number from 0"),
        (lambda: plateau_free.Annealer("paper", iterations=0), "iterations = 0 must be a whole number from 1"),
        (lambda: plateau_free.Annealer(sigma0="big"), "sigma0 = 'big' must be a number"),
        (lambda: plateau_free.Annealer.paper(0.5, 10).sigma(-1), "iteration = -1 must be a whole number from 0"),
        (lambda: plateau_free.Adam(lr=None), "lr = None must be a number"),
        (lambda: plateau_free.Adam(bounds=5), "bounds = 5 must be (lower, upper)"),
        (lambda: plateau_free.PlateauFreeGradient(staircase).estimate(None, 0.5), "x = None is not an array of numbers"),
        (lambda: plateau_free.PlateauFreeGradient(staircase).estimate([[0.0], [1.0, 2.0]], 0.5), "x = [[0.0], [1.0, 2.0]] is not an array of numbers"),
        (lambda: plateau_free.PlateauFreeGradient(staircase).estimate(X0, "wide"), "sigma = 'wide' must be a number, or one per element of x"),
        (lambda: plateau_free.Spsa(staircase).estimate(X0, None), "sigma = None must be a number"),
    ],
)
def test_the_classes_name_the_option_and_show_the_value(make, text):
    with pytest.raises(ValueError, match=re.escape(text)):
        make()


def test_option_type_error_is_a_value_error_and_a_type_error():
    assert issubclass(plateau_free.OptionTypeError, ValueError)
    assert issubclass(plateau_free.OptionTypeError, TypeError)
    assert plateau_free.OptionTypeError.__module__ == "plateau_free"
    with pytest.raises(plateau_free.OptionTypeError):
        plateau_free.minimize(staircase, X0, seed="1")
    with pytest.raises(TypeError):
        plateau_free.PlateauFreeGradient(staircase, seed="1")
    # A number out of range is a ValueError alone.
    with pytest.raises(ValueError) as info:
        plateau_free.minimize(staircase, X0, seed=-1)
    assert not isinstance(info.value, TypeError)


def test_integral_floats_and_numpy_numbers_are_accepted_where_whole_numbers_are():
    a = plateau_free.minimize(staircase, X0, budget=300.0, seed=np.uint64(3), population=np.int32(6))
    b = plateau_free.minimize(staircase, X0, budget=300, seed=3, population=6)
    assert a.x.tobytes() == b.x.tobytes() and a.nfev == b.nfev


# (method, options, the library's message): a value of the right type out of the range that
# the library checks, one per range; `fun` must never be called.
OUT_OF_RANGE = [
    ("adaptive", dict(budget=0), "budget = 0 is invalid: must be at least 1 evaluation"),
    ("adaptive", dict(sigma0=0.0), "sigma0 = 0.0 is invalid: must be finite and > 0"),
    ("adaptive", dict(sigma0=[1.0, math.inf, 1.0]), "sigma0 = inf is invalid: must be finite and > 0 (every coordinate's spread)"),
    ("adaptive", dict(target=np.float32("nan")), "target = NaN is invalid: must not be NaN"),
    ("adaptive", dict(population=np.int64(1)), "population = 1 is invalid: must be at least 2"),
    ("adaptive", dict(stop_when_stalled=0), "stop_when_stalled = 0.0 is invalid: must be a fraction of the budget in (0, 1]"),
    ("adaptive", dict(x0=[0.5, 0.5, 0.5], integrality=[0, 1, 0], bounds=[(0.2, 0.8)] * 3),
     "integrality = 1.0 is invalid: leaves no grid point k * step between a coordinate's bounds"),
    ("polished", dict(budget=100, polish=-0.25), "polish = -0.25 is invalid: must be a fraction of the budget in [0, 1)"),
    ("polished", dict(budget=100, samples=0), "samples = 0 is invalid: must be at least 1"),
    ("polished", dict(budget=100, lr=math.inf), "lr = inf is invalid: must be finite and > 0"),
    ("polished", dict(budget=100, sigma0=-2), "sigma0 = -2.0 is invalid: must be finite and > 0"),
    ("polished", dict(budget=100, stop_when_stalled=1.01), "stop_when_stalled = 1.01 is invalid"),
    ("plateau", dict(lr=-1e-3, iterations=3), "lr = -0.001 is invalid: must be finite and > 0"),
    ("plateau", dict(sigma0=0, iterations=3), "sigma0 = 0.0 is invalid: must be finite and > 0"),
    ("plateau", dict(sigma_min=math.nan, iterations=3), "sigma_min = NaN is invalid: must be finite and > 0"),
    ("plateau", dict(annealer="constant", sigma_min=-1.0, iterations=3),
     "sigma_min = -1.0 is invalid: must be finite and > 0"),
    ("spsa", dict(sigma0=-0.5, iterations=3), "sigma0 = -0.5 is invalid: must be finite and > 0"),
    ("spsa", dict(lr=0, iterations=3), "lr = 0.0 is invalid: must be finite and > 0"),
    ("fd", dict(step=-1e-3, iterations=3), "step = -0.001 is invalid: must be finite and > 0"),
    ("fd", dict(lr=math.nan, iterations=3), "lr = NaN is invalid: must be finite and > 0"),
]


@pytest.mark.parametrize("method, options, text", OUT_OF_RANGE, ids=[t for _, _, t in OUT_OF_RANGE])
def test_the_library_checks_the_ranges_before_any_evaluation(method, options, text):
    calls = []

    def counted(x):
        calls.append(x)
        return staircase(x)

    options = dict(options)
    x0 = options.pop("x0", X0)
    with pytest.raises(ValueError, match=re.escape(text)) as info:
        plateau_free.minimize(counted, x0, method=method, **options)
    assert not isinstance(info.value, TypeError)  # a number of the right type: a range error
    assert calls == []
    if method in ("adaptive", "polished", "plateau"):
        with pytest.raises(ValueError, match=re.escape(text)):
            plateau_free.ask_tell(x0, method=method, **options)


@pytest.mark.parametrize(
    "options, text",
    [
        (dict(budget=0), "budget = 0 is invalid: must be at least 1"),
        (dict(sigma0=-1.0), "sigma0 = -1.0 is invalid: must be finite and > 0"),
        (dict(pairs=0), "pairs = 0 is invalid: must be at least 1"),
        (dict(memory=0), "memory = 0 is invalid: must be at least 1"),
        (dict(damping=math.nan), "damping = NaN is invalid"),
        (dict(max_step=0.0), "max_step = 0.0 is invalid"),
    ],
)
def test_least_squares_ranges_are_the_library_s_before_any_evaluation(options, text):
    calls = []

    def residuals(x):
        calls.append(x)
        return np.asarray(x) - 1.0

    with pytest.raises(ValueError, match=re.escape(text)):
        plateau_free.least_squares(residuals, X0, **options)
    assert calls == []


@pytest.mark.parametrize(
    "options, text",
    [
        (dict(budget=2**64), "budget = 18446744073709551616 must be a whole number of evaluations, not negative"),
        (dict(population=-1), "population = -1 must be a whole number, not negative"),
        (dict(target=10**400), "target = 1000"),
        (dict(sigma0=[1.0, "a", 1.0]), "sigma0 = [1.0, 'a', 1.0] must be a number, or one per coordinate of x0"),
        (dict(stop_when_stalled=np.bool_(True)), "stop_when_stalled = True must be a number"),
    ],
)
def test_what_the_rust_side_cannot_take_is_refused_in_python(options, text):
    # Too large for the Rust side's integer, negative for a count, too large for a float, or
    # not a number: named by Python, never an OverflowError.
    with pytest.raises(ValueError) as info:
        plateau_free.minimize(staircase, X0, **options)
    assert text in str(info.value)
    assert not isinstance(info.value, OverflowError)
