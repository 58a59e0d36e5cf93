"""The stop rule ``plateau_free::Stall`` as ``stop_when_stalled`` of
:func:`plateau_free.minimize` and :func:`plateau_free.ask_tell` (methods 'adaptive' and
'polished'): a run whose best value stops improving ends one window after its last
improvement, a run still improving spends its budget, and the default runs as without the rule."""

import math

import numpy as np
import pytest

import plateau_free
from plateau_free import _native
from helpers import staircase

X0 = [0.0, 0.0, 0.0]


def floor(x):
    """Flat at 0 on the box ``|x_i| <= 1``: a floor the search reaches early and cannot beat."""
    return float(np.sum(np.maximum(np.abs(np.asarray(x, dtype=float)) - 1.0, 0.0)))


def first_stop(generations, window):
    """The Rust rule ``Stall`` (rtol 0) replayed on ``(evaluations, smallest value)`` per
    generation: the index of the generation after which it stops, or None."""
    spent, best, marks = 0, math.inf, [(0, math.inf)]
    for k, (n, value) in enumerate(generations):
        spent += n
        best = min(best, value)
        marks.append((spent, best))
        if spent < window:
            continue
        while len(marks) > 1 and marks[1][0] <= spent - window:
            marks.pop(0)
        if math.isfinite(marks[0][1]) and marks[0][1] - best <= 0.0:
            return k
    return None


def recorded(calls):
    """A batched ``floor`` that records ``(batch size, smallest value)`` of every call."""

    def fun(xs):
        values = [floor(x) for x in xs]
        calls.append((len(values), min(values)))
        return values

    return fun


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("fraction", [plateau_free.STALL_WINDOW, 0.05])
def test_a_floor_stops_one_window_after_the_last_improvement(seed, fraction):
    budget = 5000
    calls = []
    result = plateau_free.minimize(
        recorded(calls), [8.0, -6.0], budget=budget, seed=seed, batched=True,
        stop_when_stalled=fraction, patience=0,
    )  # fmt: skip
    window = math.ceil(fraction * budget)
    assert calls[0][0] == 1  # x0, alone; the rule judges from the first generation
    generations = calls[1:]
    # Stopped by the rule, at the generation where the Rust rule stops, before the budget.
    assert first_stop(generations, window) == len(generations) - 1
    assert result.nfev == sum(n for n, _ in calls) < budget
    assert (result.success, result.status) == (True, 0)
    assert result.message.startswith("stalled")
    assert f"after {result.nfev} of at most {budget} evaluations" in result.message
    assert result.fun == 0.0 == floor(result.x)
    # One window after the last improvement: the run ended at the first generation at least
    # `window` evaluations past the evaluation that found the final best.
    ends = np.cumsum([n for n, _ in generations])
    found = ends[[v for _, v in generations].index(0.0)]
    assert ends[-1] - window >= found > ends[-2] - window


def test_the_smallest_and_largest_fraction_and_the_constant():
    assert plateau_free.STALL_WINDOW == 0.2
    # A window of the whole budget can never see a full window pass: the budget ends the run.
    whole = plateau_free.minimize(floor, [8.0, -6.0], budget=600, stop_when_stalled=1.0, patience=0)
    assert whole.message.startswith("budget spent") and whole.status == 1
    # The smallest window (one evaluation, rounded up) stops at the first generation with no
    # improvement on the best.
    tiny = plateau_free.minimize(floor, [8.0, -6.0], budget=600, stop_when_stalled=1e-9, patience=0)
    assert tiny.message.startswith("stalled") and tiny.nfev < 600


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("n, budget", [(4, 200), (20, 600)])
def test_a_still_improving_run_spends_its_budget(n, budget, seed):
    # A smooth quadratic at a small budget: every window of a fifth of it improves the best.
    # (Not always at a larger one: at n = 4, budget 400, seed 5 goes 80 evaluations without
    # a new best and stops at 393: the rule cannot tell that from a floor.)
    def bowl(x):
        return float(np.sum((np.asarray(x) - 3.0) ** 2))

    off = plateau_free.minimize(bowl, [0.0] * n, budget=budget, seed=seed)
    on = plateau_free.minimize(bowl, [0.0] * n, budget=budget, seed=seed, stop_when_stalled=0.2)
    assert on.message.startswith("budget spent") and (on.success, on.status) == (False, 1)
    assert on.x.tobytes() == off.x.tobytes()
    assert (on.fun, on.nfev, on.nit, on.restarts, on.sigma) == (
        off.fun, off.nfev, off.nit, off.restarts, off.sigma
    )  # fmt: skip


@pytest.mark.parametrize("method", ["adaptive", "polished"])
def test_the_default_is_the_run_without_the_rule_bit_for_bit(method):
    options = dict(budget=700, seed=3)
    paper, polish = None, None
    if method == "polished":
        options.update(method="polished", samples=2, lr=0.05, sigma0=1.5, polish=0.5)
        paper, polish = (2, 0.05, 1.5), 0.5
    rust = _native._rust_reference_minimize_adaptive(
        X0, budget=700, seed=3, paper=paper, polish=polish
    )
    for result in (
        plateau_free.minimize(staircase, X0, **options),
        plateau_free.minimize(staircase, X0, stop_when_stalled=None, **options),
    ):
        assert result.x.tobytes() == rust["x"].tobytes()
        assert (result.fun, result.nfev, result.nit, result.restarts, result.sigma) == (
            rust["fun"], rust["nfev"], rust["nit"], rust["restarts"], rust["sigma"]
        )  # fmt: skip
        assert result.message.startswith(rust["stop"])


def test_polished_is_judged_from_the_hand_over():
    budget, calls = 4000, []
    result = plateau_free.minimize(
        recorded(calls), [8.0, -6.0], method="polished", budget=budget, polish=0.5, samples=2,
        batched=True, stop_when_stalled=0.2, patience=0,
    )  # fmt: skip
    assert result.message.startswith("stalled") and (result.success, result.status) == (True, 0)
    assert result.fun == 0.0 and result.nfev == sum(n for n, _ in calls) < budget
    # The paper's loop evaluates 2 points an iteration (and single points); the adaptive search
    # a population of at least 4 + floor(3 ln 2) = 6: its generations start at the hand-over.
    handover = next(k for k, (n, _) in enumerate(calls) if n >= 6)
    generations = calls[handover:]
    assert all(n >= 6 for n, _ in generations)
    assert sum(n for n, _ in calls[:handover]) >= 0.4 * budget  # the loop ran its share
    # The rule, with its window a fraction of the whole budget, judged the polish alone.
    assert first_stop(generations, math.ceil(0.2 * budget)) == len(generations) - 1


@pytest.mark.parametrize("method", ["adaptive", "polished"])
def test_ask_tell_is_minimize_with_the_rule(method):
    options = dict(budget=3000, seed=4, stop_when_stalled=0.1, patience=0)
    if method == "polished":
        options.update(method="polished", samples=2)
    expected = plateau_free.minimize(floor, [8.0, -6.0], **options)
    es = plateau_free.ask_tell([8.0, -6.0], **options)
    while not es.done:
        xs, _ = es.ask()
        es.tell([floor(x) for x in xs])
    got = es.result
    assert expected.message.startswith("stalled")
    assert got.x.tobytes() == expected.x.tobytes()
    assert (got.fun, got.nfev, got.nit, got.status, got.message) == (
        expected.fun, expected.nfev, expected.nit, expected.status, expected.message
    )  # fmt: skip
