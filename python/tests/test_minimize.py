"""plateau_free.minimize: the result, the history, callbacks, bounds, annealers, baselines."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import plateau_free

A = np.array([1.0, 2.0])


def step(x):
    return float(x @ A > 0.3)


def test_leaves_the_plateau_and_reports_like_scipy():
    result = plateau_free.minimize(step, [1.0, 1.0], method="plateau", sigma0=0.5, iterations=200, samples=8, seed=7)
    assert result.x @ A < 0.3
    # All iterations done: scipy's "iteration limit reached" (the loop never tests convergence).
    assert result.fun == 0.0 and not result.success and result.status == 1
    assert result.nit == 200 and result.nfev == 200 * 8 + 1
    assert "completed 200 iterations" in result.message
    assert not result.from_checkpoint
    assert set(result) >= {"x", "fun", "nit", "nfev", "success", "message", "history"}
    assert result["x"] is result.x
    h = result.history
    assert len(h) == 200 and h.x is None
    np.testing.assert_array_equal(h.sigma, plateau_free.Annealer.paper(0.5, 200).sigmas())
    assert h.grad_norm.shape == h.fun.shape == h.nfev.shape == (200,)
    assert h.nfev[-1] == 1600 and np.all(h.grad_norm >= 0)
    assert "nfev" in repr(result)


def test_callback_returning_true_stops_the_run():
    seen = []

    def callback(x):
        seen.append(x.copy())
        return len(seen) == 3

    result = plateau_free.minimize(step, [1.0, 1.0], method="plateau", iterations=100, callback=callback)
    assert result.nit == 3 and len(result.history) == 3 and result.status == 99 and not result.success
    assert result.message == "stopped by the callback (it returned a true value) after iteration 3"
    np.testing.assert_array_equal(seen[-1], result.x)


def test_callback_with_intermediate_result():
    seen = []

    def callback(intermediate_result):
        seen.append(intermediate_result)
        return intermediate_result.nit >= 4

    result = plateau_free.minimize(step, [1.0, 1.0], method="plateau", iterations=100, samples=4, callback=callback)
    assert result.nit == 4
    last = seen[-1]
    assert last.nit == 4 and last.nfev == 16 and last.sigma == 0.5 and last.jac.shape == (2,)
    assert isinstance(last.fun, float)
    # A callback returning None or False goes on.
    assert plateau_free.minimize(step, [1.0, 1.0], method="plateau", iterations=5, callback=lambda x: None).nit == 5
    assert plateau_free.minimize(step, [1.0, 1.0], method="plateau", iterations=5, callback=lambda x: 0).nit == 5


def test_bounds_hold_after_every_step():
    bounds = [(0.5, 2.0), (None, 0.9)]
    result = plateau_free.minimize(step, [1.0, 0.5], method="plateau", iterations=50, samples=4, bounds=bounds, record_x=True)
    xs = result.history.x
    assert xs.shape == (50, 2)
    assert np.all(xs[:, 0] >= 0.5) and np.all(xs[:, 0] <= 2.0) and np.all(xs[:, 1] <= 0.9)
    one_pair = plateau_free.minimize(step, [0.5, 0.5], method="plateau", iterations=20, bounds=(0.4, 0.6), record_x=True)
    assert np.all(one_pair.history.x >= 0.4) and np.all(one_pair.history.x <= 0.6)


@pytest.mark.parametrize("method", ["adaptive", "plateau", "polished", "fd", "spsa"])
def test_x0_outside_the_bounds_is_an_error_for_every_method(method):
    # Every method, the paper's loop included, refuses an x0 outside the box.
    with pytest.raises(ValueError, match=r"x0\[1\] = 0\.7 is outside bounds\[1\] = \(0\.4, 0\.6\)"):
        plateau_free.minimize(step, [0.5, 0.7], method=method, budget=100, bounds=(0.4, 0.6))
    with pytest.raises(ValueError, match=r"x0\[0\] = -1 is outside bounds\[0\] = \(0, 1\)"):
        plateau_free.ask_tell([-1, 0.5], method=method if method not in ("fd", "spsa") else "plateau", budget=100, bounds=[(0, 1), (0, 1)])


def test_scipy_style_bounds_object():
    class Bounds:
        lb = np.array([0.0, 0.0])
        ub = np.array([0.1, 0.1])

    result = plateau_free.minimize(step, [0.05, 0.05], method="plateau", iterations=10, bounds=Bounds())
    assert np.all(result.x >= 0.0) and np.all(result.x <= 0.1)


@pytest.mark.parametrize("annealer", ["paper", "constant", "exponential", "cosine"])
def test_every_annealer(annealer):
    result = plateau_free.minimize(step, [1.0, 1.0], method="plateau", iterations=30, annealer=annealer, sigma0=0.4)
    expected = plateau_free.Annealer(annealer, sigma0=0.4, iterations=30).sigmas()
    np.testing.assert_array_equal(result.history.sigma, expected)


def test_annealer_object_sets_the_length():
    result = plateau_free.minimize(step, [1.0, 1.0], method="plateau", annealer=plateau_free.Annealer.cosine(0.3, 0.02, 25))
    assert result.nit == 25 and result.history.sigma[0] == 0.3


def test_baselines_on_the_same_loop():
    # On the plateau the finite difference sees nothing: x does not move.
    fd = plateau_free.minimize(step, [1.0, 1.0], iterations=20, method="fd")
    np.testing.assert_array_equal(fd.x, [1.0, 1.0])
    assert fd.nfev == 20 * 4 + 1
    spsa = plateau_free.minimize(lambda x: float(x @ x), [1.0, 1.0], iterations=50, method="spsa", lr=0.05)
    assert spsa.x @ spsa.x < 2.0


def test_budget_sets_the_iterations():
    # The final evaluation is paid from the budget: (400 - 1) // 4 iterations.
    result = plateau_free.minimize(step, [1.0, 1.0], method="plateau", budget=400, samples=4)
    assert result.nit == 99 and result.nfev == 397
    with pytest.raises(ValueError, match="budget = 4 cannot pay for one iteration"):
        plateau_free.minimize(step, [1.0, 1.0], method="plateau", budget=4, samples=4)


def test_final_evaluation_can_be_skipped():
    result = plateau_free.minimize(step, [1.0, 1.0], method="plateau", iterations=10, final_evaluation=False)
    assert result.nfev == 20 and result.fun == result.history.fun[-1]


def test_two_dimensional_x0():
    target = np.arange(6.0).reshape(2, 3) / 10
    result = plateau_free.minimize(lambda x: float(((x - target) ** 2).sum()), np.zeros((2, 3)), method="plateau", iterations=300, lr=0.01, samples=4)
    assert result.x.shape == (2, 3)
    assert np.abs(result.x - target).max() < 0.05


def test_dimension_1e5():
    n = 100_000
    result = plateau_free.minimize(lambda X: (X**2).sum(axis=1), np.ones(n), method="plateau", iterations=5, batched=True, samples=2)
    assert result.x.shape == (n,) and result.nit == 5 and np.all(np.isfinite(result.x))
    assert np.isfinite(result.fun) and len(result.history) == 5


@pytest.mark.parametrize("method", ["plateau", "fd", "spsa"])
def test_the_history_keeps_the_last_iterations(method):
    # The per-iteration history is bounded, so that a long run's memory is too: it keeps the
    # last keep_history iterations (default a million).
    full = plateau_free.minimize(step, [1.0, 1.0], method=method, iterations=1000, record_x=True, seed=3)
    kept = plateau_free.minimize(step, [1.0, 1.0], method=method, iterations=1000, record_x=True, seed=3, keep_history=7)
    assert kept.x.tobytes() == full.x.tobytes() and kept.nit == 1000 and kept.nfev == full.nfev
    h = kept.history
    assert len(h) == 7 and h.dropped == 993 and full.history.dropped == 0
    for name in ("sigma", "grad_norm", "fun", "nfev", "x"):
        np.testing.assert_array_equal(getattr(h, name), getattr(full.history, name)[-7:])
    assert "993 earlier dropped" in repr(h)
    es = plateau_free.ask_tell([1.0, 1.0], method="plateau", iterations=50, keep_history=3, seed=3)
    while not es.done:
        X, _ = es.ask()
        es.tell([step(x) for x in X])
    assert len(es.result.history) == 3 and es.result.history.dropped == 47


def test_a_long_run_holds_a_bounded_history():
    kept = plateau_free.minimize(lambda X: np.zeros(len(X)), np.zeros(3), method="plateau", batched=True,
                                 iterations=300_000, keep_history=1000, final_evaluation=False)
    assert kept.nit == 300_000 and len(kept.history) == 1000 and kept.history.dropped == 299_000
    assert kept.history.nfev[-1] == kept.nfev == 600_000


def test_a_million_iterations_stay_within_their_kept_history():
    # A million paper-loop iterations keep 10^5 of them, and memory grows by the kept history
    # alone (under 20 MB). In a fresh interpreter, so that the peak resident memory is this run's.
    script = textwrap.dedent(
        """
        import resource, numpy as np, plateau_free
        zero = lambda X: np.zeros(len(X))
        plateau_free.minimize(zero, np.zeros(3), method="plateau", batched=True, iterations=10)
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        r = plateau_free.minimize(zero, np.zeros(3), method="plateau", batched=True,
                                  iterations=10**6, final_evaluation=False, keep_history=10**5)
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        print(r.nit, len(r.history), r.history.dropped, before // 1024, peak // 1024)
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    nit, held, dropped, before_mb, peak_mb = map(int, done.stdout.split())
    assert (nit, held, dropped) == (10**6, 10**5, 9 * 10**5)
    # The record of the last 10^5 iterations, 32 bytes each, at most twice that while running;
    # without a bound, 10^6 x 48 bytes.
    assert peak_mb - before_mb < 20, (before_mb, peak_mb)
