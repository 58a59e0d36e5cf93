"""plateau_free.ask_tell: the caller evaluates the points; the result is plateau_free.minimize's, bit for
bit, for both methods; asking twice, telling without asking, the wrong number of values and
non-finite values are ValueErrors that change nothing."""

import numpy as np
import pytest

import plateau_free

TARGET = np.array([1.0, -2.0, 3.0])


def stairs(x):
    """Flat almost everywhere: the squared distance of the rounded point to TARGET."""
    return float(np.sum((np.floor(x + 0.5) - TARGET) ** 2))


def noisy(x, seed):
    """The staircase with noise that depends on the seed alone (a renderer's noise)."""
    return stairs(x) + 1e-3 * float(int(seed) % 97)


def run(es, fun, seeded=False):
    """Ask and tell until done, evaluating the points last to first (order must not matter)."""
    asks = 0
    while not es.done:
        X, seeds = es.ask()
        assert X.dtype == np.float64 and seeds.dtype == np.uint64
        assert X.shape[0] == seeds.shape[0] >= 1
        values = [0.0] * len(X)
        for k in reversed(range(len(X))):
            values[k] = fun(X[k], seeds[k]) if seeded else fun(X[k])
        es.tell(values)
        asks += 1
    return es.result, asks


def assert_same_result(told, called):
    assert set(told) == set(called)
    for key in called:
        if key == "history":
            continue
        if isinstance(called[key], np.ndarray):
            np.testing.assert_array_equal(told[key], called[key])
            assert told[key].shape == called[key].shape
        else:
            assert told[key] == called[key], key
    if told.history is None:  # the adaptive search: minimize's driver keeps the history
        assert called.history is None or isinstance(called.history, plateau_free.SearchHistory)
        return
    for field in ("sigma", "grad_norm", "fun", "nfev"):
        np.testing.assert_array_equal(getattr(told.history, field), getattr(called.history, field))
    if called.history.x is None:
        assert told.history.x is None
    else:
        np.testing.assert_array_equal(told.history.x, called.history.x)


@pytest.mark.parametrize("seed", [0, 1, 7])
def test_adaptive_ask_tell_is_minimize(seed):
    options = dict(budget=1500, seed=seed)
    called = plateau_free.minimize(stairs, [0.0, 0.0, 0.0], **options)
    told, asks = run(plateau_free.ask_tell([0.0, 0.0, 0.0], **options), stairs)
    assert_same_result(told, called)
    assert told.fun == 0.0 and told.message.startswith("done")
    assert told.success and told.status == 0
    assert asks == told.nit + 1  # the start, asked alone first, then one ask per generation
    # With bounds, a target and a seeded, noisy objective.
    options = dict(budget=1200, seed=seed, bounds=[(-5, 5)] * 3, target=0.05, population=8)
    called = plateau_free.minimize(noisy, [0.0, 0.0, 0.0], seeded=True, **options)
    told, _ = run(plateau_free.ask_tell([0.0, 0.0, 0.0], **options), noisy, seeded=True)
    assert_same_result(told, called)
    # A batched objective gets the same points and seeds.
    batched = plateau_free.minimize(
        lambda X, s: np.array([noisy(x, k) for x, k in zip(X, s)]),
        [0.0, 0.0, 0.0],
        batched=True,
        seeded=True,
        **options,
    )
    assert_same_result(told, batched)


@pytest.mark.parametrize("seed", [0, 3])
def test_paper_loop_ask_tell_is_minimize(seed):
    options = dict(method="plateau", sigma0=1.0, iterations=120, lr=0.05, samples=4, seed=seed, record_x=True)
    called = plateau_free.minimize(noisy, [0.0, 0.0, 0.0], seeded=True, **options)
    es = plateau_free.ask_tell([0.0, 0.0, 0.0], **options)
    assert es.method == "plateau"
    told, asks = run(es, noisy, seeded=True)
    assert_same_result(told, called)
    assert asks == 121  # 120 estimates and the final evaluation
    assert told.nfev == 120 * 4 + 1 and told.history.x.shape == (120, 3)
    # Every option of the paper's loop; no final evaluation; method spelt 'paper'.
    options = dict(
        method="paper",
        budget=600,
        sigma0=0.8,
        lr=0.03,
        samples=6,
        sampling="gaussian",
        orthogonal=True,
        annealer="cosine",
        sigma_min=0.05,
        bounds=[(-4, 4)] * 3,
        seed=seed,
        final_evaluation=False,
    )
    told, asks = run(plateau_free.ask_tell([0.5, 0.5, 0.5], **options), stairs)
    options["method"] = "plateau"
    called = plateau_free.minimize(stairs, [0.5, 0.5, 0.5], **options)
    assert_same_result(told, called)
    assert asks == 100 and told.nfev == 600


def test_the_seeds_are_those_a_seeded_fun_receives():
    seen = []

    def logged(x, seed):
        seen.append(int(seed))
        return noisy(x, seed)

    plateau_free.minimize(logged, [0.0, 0.0, 0.0], method="plateau", seeded=True, samples=4, iterations=10, seed=5)
    es = plateau_free.ask_tell([0.0, 0.0, 0.0], method="plateau", samples=4, iterations=10, seed=5)
    asked = []
    while not es.done:
        X, seeds = es.ask()
        asked.extend(int(s) for s in seeds)
        es.tell([noisy(x, s) for x, s in zip(X, seeds)])
    assert asked == seen
    assert asked[0] == asked[1] != asked[2]  # one seed per antithetic pair
    assert asked[-1] == 5  # the final evaluation gets the run's seed


def test_points_have_the_shape_of_x0():
    x0 = np.zeros((2, 3))
    es = plateau_free.ask_tell(x0, budget=100)
    X, seeds = es.ask()
    assert X.shape == (len(seeds), 2, 3)
    es.tell(np.array([float(np.sum(x**2)) for x in X]).reshape(-1, 1))  # any shape of k values
    assert es.nfev == len(seeds)
    x, fun = es.best
    assert x.shape == (2, 3) and fun == min(float(np.sum(x**2)) for x in X)


@pytest.mark.parametrize("method", ["adaptive", "plateau"])
def test_errors_are_value_errors_that_change_nothing(method):
    options = dict(budget=400, seed=2) if method == "adaptive" else dict(method="plateau", iterations=30, seed=2)
    options["on_failure"] = "raise"  # non-finite values refused
    clean, _ = run(plateau_free.ask_tell([0.5, 0.5, 0.5], **options), stairs)
    es = plateau_free.ask_tell([0.5, 0.5, 0.5], **options)
    with pytest.raises(ValueError, match="tell without ask"):
        es.tell([1.0])
    with pytest.raises(ValueError, match="not ended"):
        es.result
    iteration = 0
    while not es.done:
        X, _ = es.ask()
        values = [stairs(x) for x in X]
        if iteration == 3:
            with pytest.raises(ValueError, match="ask called twice"):
                es.ask()
            with pytest.raises(ValueError, match=f"tell got {len(X) - 1} values for {len(X)} asked points"):
                es.tell(values[:-1])
            bad = list(values)
            bad[1] = float("nan")
            with pytest.raises(ValueError, match="f returned NaN at evaluation"):
                es.tell(bad)
            bad[1] = float("inf")
            with pytest.raises(ValueError, match="inf"):
                es.tell(bad)
            with pytest.raises(ValueError, match="could not convert"):
                es.tell(["one"] * len(X))
        es.tell(values)
        iteration += 1
    assert_same_result(es.result, clean)
    with pytest.raises(ValueError, match="has ended"):
        es.ask()
    with pytest.raises(ValueError, match="tell without ask"):
        es.tell([1.0])
    assert "done" in repr(es)


def test_bad_options_are_value_errors():
    with pytest.raises(ValueError, match="empty"):
        plateau_free.ask_tell([], budget=10)
    with pytest.raises(ValueError, match="budget"):
        plateau_free.ask_tell([1.0], budget=0)
    with pytest.raises(ValueError, match="not finite"):
        plateau_free.ask_tell([float("nan")], budget=10)
    with pytest.raises(ValueError, match="even number of samples"):
        plateau_free.ask_tell([1.0], method="plateau", samples=3, iterations=5)
    with pytest.raises(ValueError, match="lr = 0.1: not an option of method='adaptive'"):
        plateau_free.ask_tell([1.0], budget=10, method="adaptive", lr=0.1)
    with pytest.raises(ValueError, match="samples = 4: not an option of method='adaptive'"):
        plateau_free.ask_tell([1.0], samples=4)  # never a silent switch to the paper's loop
    # An option of minimize alone is named as such, not as another method's.
    with pytest.raises(ValueError, match=r"^disp = True: not an option of ask_tell, an option of minimize \("):
        plateau_free.ask_tell([1.0], budget=10, disp=True)
    with pytest.raises(ValueError, match="minimize's alone"):
        plateau_free.ask_tell([1.0], budget=10, method="fd")
    with pytest.raises(ValueError, match="on_failure = 'skip' is not a policy"):
        plateau_free.ask_tell([1.0], budget=10, on_failure="skip")
    with pytest.raises(TypeError, match="use budget="):
        plateau_free.ask_tell([1.0], maxfev=10)
    plateau_free.ask_tell([1.0], budget=10, bounds=[(None, 2.0)])  # one side open
