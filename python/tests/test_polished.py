"""`minimize(fun, x0, method='polished', budget=...)`: the paper's loop on the first
`1 - polish` of the budget, then the adaptive search from its best point (the Rust
`Minimizer::strategy(Strategy::Paper {..}).polish(..)`)."""

import math

import numpy as np
import pytest

import plateau_free
from plateau_free import _native
from helpers import staircase, staircase_batch, staircase_seeded

TIP = np.array([0.3, -0.2])
START = [1.5, 0.8]  # 1.6 from the tip: on the plateau
LOOP = {"samples": 2, "lr": 0.02, "sigma0": 1.0}


def cone_in_a_plateau(x):
    """A cone of radius 1 in a plateau, as an image loss near its optimum: the distance to the
    tip inside, 1 outside."""
    return min(math.sqrt(float(np.sum((x - TIP) ** 2))), 1.0)


@pytest.mark.parametrize("seed", range(5))
def test_the_polish_finishes_the_papers_loop(seed):
    polished = plateau_free.minimize(
        cone_in_a_plateau, START, method="polished", budget=800, seed=seed, **LOOP
    )
    # The same loop alone on the same budget: 399 iterations of 2 evaluations and the final
    # one, 799 in all.
    alone = plateau_free.minimize(
        cone_in_a_plateau, START, method="plateau", budget=800, seed=seed, **LOOP
    )
    assert alone.nit == 399 and alone.nfev == 799
    assert alone.fun < 1.0, f"the loop found the cone: {alone.fun}"
    assert alone.fun > 1e-7, f"the loop alone hovers around the tip: {alone.fun}"
    # 5 to 360 times closer (seeds 0 to 4; the start's evaluation comes out of the budget).
    assert polished.fun < 0.25 * alone.fun, (polished.fun, alone.fun)
    assert polished.fun == cone_in_a_plateau(polished.x)  # the best point seen, its value
    assert polished.nfev == 800
    assert polished.nit > 199  # the loop's iterations (400 evaluations), then generations
    assert polished.message.startswith("budget spent") and polished.status == 1 and not polished.success
    assert isinstance(polished.restarts, int) and polished.sigma > 0.0
    assert isinstance(polished.history, plateau_free.SearchHistory) and polished.x.shape == (2,)
    again = plateau_free.minimize(
        cone_in_a_plateau, START, method="polished", budget=800, seed=seed, **LOOP
    )
    assert again.x.tobytes() == polished.x.tobytes() and again.fun == polished.fun
    assert (again.nit, again.nfev, again.sigma) == (polished.nit, polished.nfev, polished.sigma)


def same(result, rust):
    assert result.x.tobytes() == rust["x"].tobytes()
    assert result.fun == rust["fun"]
    assert (result.nfev, result.nit) == (rust["nfev"], rust["nit"])
    assert (result.restarts, result.sigma) == (rust["restarts"], rust["sigma"])
    assert result.message.startswith(rust["stop"])


@pytest.mark.parametrize("polish", [0.0, 0.25, 0.6])
def test_bit_identical_to_the_rust_minimizer(polish):
    x0 = [0.0, 0.0, 0.0]
    paper = (2, 0.05, 1.5)
    rust = _native._rust_reference_minimize_adaptive(
        x0, budget=700, seed=3, paper=paper, polish=polish
    )
    options = dict(method="polished", budget=700, seed=3, samples=2, lr=0.05, sigma0=1.5)
    same(plateau_free.minimize(staircase, x0, polish=polish, **options), rust)
    same(plateau_free.minimize(staircase_batch, x0, polish=polish, batched=True, **options), rust)
    # Ask and tell: the same run, its points evaluated here.
    es = plateau_free.ask_tell(x0, polish=polish, **options)
    assert es.method == "polished"
    while not es.done:
        X, _ = es.ask()
        es.tell([staircase(x) for x in X])
    same(es.result, rust)
    assert es.best[1] == rust["fun"]


def test_seeded_and_bounded_bit_identical():
    x0 = [0.5, -0.5, 0.5]
    bounds = ([-4.0] * 3, [4.0] * 3)
    rust = _native._rust_reference_minimize_adaptive(
        x0, budget=500, seed=11, bounds=bounds, seeded=True, paper=(2, 0.02, 0.5), polish=0.5
    )
    result = plateau_free.minimize(
        staircase_seeded, x0, method="polished", budget=500, seed=11, bounds=(-4.0, 4.0), seeded=True
    )
    same(result, rust)  # the defaults: samples 2, lr 0.02, sigma0 0.5, polish 0.5


def test_callback_sees_every_iteration_and_can_stop():
    seen = []

    def callback(intermediate_result):
        seen.append((intermediate_result.nit, intermediate_result.nfev))
        return intermediate_result.nit == 5

    result = plateau_free.minimize(
        cone_in_a_plateau, START, method="polished", budget=800, callback=callback, **LOOP
    )
    # The start (one evaluation), then one gradient estimate per iteration.
    assert seen == [(k, 2 * k + 1) for k in range(1, 6)]
    assert result.message == "stopped by the callback (it returned a true value) after iteration 5"
    assert result.status == 99 and not result.success
    assert result.nfev == 11 and result.restarts is None and result.sigma is None


def test_target_stops_the_run():
    result = plateau_free.minimize(
        cone_in_a_plateau, START, method="polished", budget=800, target=0.05, **LOOP
    )
    assert result.fun <= 0.05 and result.message == "target reached" and result.nfev < 800
    assert result.success and result.status == 0


@pytest.mark.parametrize("polish", [1.0, -0.1, math.nan, math.inf, True, "0.5"])
def test_bad_polish(polish):
    with pytest.raises(ValueError, match=r"polish = .* (is invalid: must be a fraction of the budget in \[0, 1\)|must be a number)"):
        plateau_free.minimize(cone_in_a_plateau, START, method="polished", budget=100, polish=polish)
    with pytest.raises(ValueError, match=r"polish = .* (is invalid: must be a fraction|must be a number)"):
        plateau_free.ask_tell(START, method="polished", budget=100, polish=polish)


@pytest.mark.parametrize("method", [None, "adaptive", "plateau", "fd", "spsa"])
def test_polish_belongs_to_method_polished(method):
    named = rf"polish = 0.25: not an option of method='{method or 'adaptive'}'.*, an option of method='polished'"
    with pytest.raises(ValueError, match=named):
        plateau_free.minimize(cone_in_a_plateau, START, method=method, budget=100, polish=0.25)
    if method in (None, "adaptive", "plateau"):
        with pytest.raises(ValueError, match=named):
            plateau_free.ask_tell(START, method=method, budget=100, polish=0.25)


def test_options_that_do_not_apply():
    def run(**options):
        return plateau_free.minimize(cone_in_a_plateau, START, method="polished", **options)

    with pytest.raises(ValueError, match="budget: method='polished' needs one"):
        run()
    with pytest.raises(ValueError, match="budget: method='polished' needs one"):
        plateau_free.ask_tell(START, method="polished")
    with pytest.raises(
        ValueError,
        match="iterations = 10: not an option of method='polished', an option of method='plateau', 'fd' or 'spsa'; "
        "annealer = 'cosine': not an option of method='polished', an option of method='plateau' or 'spsa'",
    ):
        run(budget=100, iterations=10, annealer="cosine")
    for name, value in [("sampling", "gaussian"), ("antithetic", False), ("sigma_min", 0.1), ("step", 0.1),
                        ("orthogonal", True), ("parallel", True), ("record_x", True), ("final_evaluation", False)]:
        with pytest.raises(ValueError, match=f"{name} = {value!r}: not an option of method='polished'"):
            run(budget=100, **{name: value})


def test_bad_loop_options():
    def run(**options):
        return plateau_free.minimize(cone_in_a_plateau, START, method="polished", budget=100, **options)

    for samples in (0, -2, 2.5, True):
        with pytest.raises(ValueError, match=rf"samples = {samples!r} (is invalid: must be at least 1|must be a whole number)"):
            run(samples=samples)
    with pytest.raises(ValueError, match="samples = 3: antithetic pairs need an even number of samples; use an even count$"):
        run(samples=3)
    for name in ("lr", "sigma0"):
        for value in (0.0, -1.0, math.nan, math.inf):
            with pytest.raises(ValueError, match=f"{name} = {'NaN' if math.isnan(value) else repr(value)} is invalid: must be finite and > 0"):
                run(**{name: value})
    with pytest.raises(ValueError, match=r"x0\[0\] = 1\.5 is outside bounds\[0\] = \(None, 1\.0\)"):
        run(bounds=[(None, 1.0), (-1.0, 1.0)])
    with pytest.raises(ValueError, match="population = 1 is invalid: must be at least 2"):
        run(population=1)
