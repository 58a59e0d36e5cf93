"""plateau_free.nevergrad: our search in nevergrad's registry, run by nevergrad's ``minimize`` on
nevergrad's own functions.

nevergrad is a test requirement (python/requirements-test.txt, installed by scripts/test-all):
these tests fail, never skip, when it is missing.
"""

from __future__ import annotations

import concurrent.futures
import nevergrad as ng
import numpy as np
import pytest
from nevergrad.functions import ArtificialFunction
from nevergrad.functions import corefuncs

import plateau_free
import plateau_free.nevergrad as pfng


def _optimizer(name: str, dimension: int, budget: int, seed: int) -> ng.optimizers.base.Optimizer:
    param = ng.p.Array(shape=(dimension,))
    param.random_state = np.random.RandomState(seed)
    return ng.optimizers.registry[name](parametrization=param, budget=budget)


def test_importing_the_module_registers_the_optimizers() -> None:
    assert ng.optimizers.registry["PlateauFree"] is pfng.PlateauFree
    assert ng.optimizers.registry["PlateauFreePaper"] is pfng.PlateauFreePaper
    assert ng.optimizers.PlateauFree is pfng.PlateauFree
    assert repr(pfng.PlateauFree) == "PlateauFree"


def test_it_minimises_nevergrads_functions_within_the_budget() -> None:
    # nevergrad's benchmark functions, translated at random (seeded): a sphere, and a step
    # ellipsoid, step(w . x^2) with step(s) = exp(int(log s)), whose gradient is zero wherever
    # it exists; from the origin it starts at exp(3) (the translation and weights 1 to 1e6).
    # Below 1 from exp(13): 14 plateaus left behind.
    for name, tolerance in [("sphere", 1e-8), ("stepellipsoid", 1.0)]:
        func = ArtificialFunction(name, block_dimension=4)
        func.parametrization.random_state.seed(0)
        calls = []

        def counted(x: np.ndarray) -> float:
            calls.append(1)
            return float(func(x))

        start = counted(np.zeros(4))
        opt = _optimizer("PlateauFree", 4, 1500, 0)
        recommendation = opt.minimize(counted)
        assert len(calls) == 1501 and opt.num_ask == 1500 and opt.num_tell == 1500
        assert func(recommendation.value) <= tolerance < start, (name, start, func(recommendation.value))


def test_the_paper_loop_leaves_a_plateau_of_a_core_function() -> None:
    # nevergrad's stepdoublelinearslope, step(|sum x|): 1 for every |sum x| in (1/e, e).
    f = corefuncs.registry["stepdoublelinearslope"]
    start = np.full(3, 0.5)
    assert f(start) == 1.0
    for seed in range(3):
        param = ng.p.Array(init=start)
        param.random_state = np.random.RandomState(seed)
        opt = ng.optimizers.registry["PlateauFreePaper"](parametrization=param, budget=400)
        recommendation = opt.minimize(f)
        assert f(recommendation.value) <= np.exp(-1.0), (seed, recommendation.value)


def test_a_seeded_run_repeats_and_is_ask_tells_run() -> None:
    def f(x: np.ndarray) -> float:
        return float(corefuncs.registry["stepellipsoid"](x - 1.5))

    def run(seed: int) -> np.ndarray:
        return np.asarray(_optimizer("PlateauFree", 3, 600, seed).minimize(f).value)

    a, b, c = run(5), run(5), run(6)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    # The seed nevergrad's random state gives, in plateau_free.minimize: the same bits (an
    # unbounded Array's standardized data is its value).
    seed = int(np.random.RandomState(5).randint(2**31 - 1))
    direct = plateau_free.minimize(f, np.zeros(3), budget=600, seed=seed, sigma0=1.0)
    assert np.array_equal(a, direct.x)
    # Seeding after the optimizer is made (nevergrad's usual way) works as well.
    opt = ng.optimizers.registry["PlateauFree"](parametrization=3, budget=600)
    opt.parametrization.random_state = np.random.RandomState(5)
    assert np.array_equal(np.asarray(opt.minimize(f).value), a)


def test_the_order_of_the_tells_does_not_matter() -> None:
    f = corefuncs.registry["sphere"]

    def run(reverse: bool) -> np.ndarray:
        opt = _optimizer("PlateauFree", 4, 400, 2)
        while opt.num_tell < 400:
            # One batch of ours: ask until the batch is handed out (a known size here: the
            # first ask queues it), tell in either order.
            first = opt.ask()
            batch = [first] + [opt.ask() for _ in range(len(opt._queue))]
            for candidate in reversed(batch) if reverse else batch:
                opt.tell(candidate, f(candidate.value))
        return np.asarray(opt.provide_recommendation().value)

    assert np.array_equal(run(False), run(True))


def test_bad_use_is_an_error_naming_it() -> None:
    with pytest.raises(ValueError, match="population"):
        pfng.ParametrizedPlateauFree(population=-1)
    with pytest.raises(ValueError, match="seed"):
        pfng.ParametrizedPlateauFree(seed=3)
    with pytest.raises(ValueError, match="budget"):
        ng.optimizers.registry["PlateauFree"](parametrization=2, budget=None)
    opt = ng.optimizers.registry["PlateauFree"](parametrization=2, budget=100)
    opt.ask()  # hands out the first point of a batch, queues the rest
    for _ in range(len(opt._queue)):
        opt.ask()
    with pytest.raises(RuntimeError, match="sequential"):
        opt.ask()


def test_dimension_one_and_a_configured_variant() -> None:
    f = corefuncs.registry["sphere"]
    opt = _optimizer("PlateauFree", 1, 200, 0)
    assert abs(opt.minimize(f).value[0]) < 1e-3
    small = pfng.ParametrizedPlateauFree(population=4, restarts=False)
    opt = small(parametrization=ng.p.Array(shape=(20,)), budget=300)
    value = opt.minimize(f).value
    assert value.shape == (20,) and f(value) < f(np.zeros(20)) + 1e-12


def test_several_workers_are_accepted() -> None:
    # nevergrad keeps 4 candidates in flight: a batch's values still go to the run in order.
    f = corefuncs.registry["sphere"]
    param = ng.p.Array(shape=(3,))
    param.random_state = np.random.RandomState(5)
    opt = ng.optimizers.registry["PlateauFree"](parametrization=param, budget=600, num_workers=4)
    assert f(opt.minimize(f).value) < 1e-3
    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        param = ng.p.Array(shape=(3,))
        param.random_state = np.random.RandomState(5)
        opt = ng.optimizers.registry["PlateauFree"](parametrization=param, budget=600, num_workers=4)
        value = opt.minimize(f, executor=pool).value
    assert f(value) < 1e-2
