"""plateau_free.torch.wrap: a black box as a torch.autograd.Function whose backward is the
plateau-free estimate. The gradient averaged over many seeds is the analytic gradient of the
Gaussian-smoothed step and staircase (within 4 standard errors computed from the samples); for
one seed it is bit for bit PlateauFreeGradient's first estimate with that seed; image-valued f
under a differentiable loss; a torch.optim run. PyTorch is a test requirement
(python/requirements-test.txt): these tests fail, never skip, when it is missing."""

from __future__ import annotations

import doctest

import numpy as np
import pytest
import torch

import plateau_free
import plateau_free.torch
from helpers import assert_mean_matches, floor_sum, smoothed_floor_gradient, smoothed_step_gradient


def gradient(g, theta, seed):
    t = torch.tensor(theta, dtype=torch.float64, requires_grad=True)
    (grad,) = torch.autograd.grad(g(t, seed), t)
    return grad.numpy()


@pytest.mark.parametrize("theta, a, sigma", [(0.0, 0.3, 0.5), (1.0, 0.2, 0.1), (-3.0, 2.0, 4.0)])
def test_the_mean_over_seeds_is_the_smoothed_step_gradient(theta, a, sigma):
    g = plateau_free.torch.wrap(lambda x: float(x[0] > a), sigma=sigma)
    grads = [gradient(g, [theta], seed)[0] for seed in range(4000)]
    assert_mean_matches(grads, smoothed_step_gradient(theta, a, sigma), "step")


@pytest.mark.parametrize("sampling", ["radial", "per_coordinate", "gaussian"])
def test_the_mean_over_seeds_is_the_smoothed_staircase_gradient(sampling):
    theta, sigma = [0.3, -1.2, 2.5], 0.4
    g = plateau_free.torch.wrap(floor_sum, sigma=sigma, samples=8, sampling=sampling)
    grads = [gradient(g, theta, seed) for seed in range(3000)]
    assert_mean_matches(grads, [smoothed_floor_gradient(t, sigma) for t in theta], f"staircase, {sampling}")


@pytest.mark.parametrize("options", [{}, {"samples": 6, "sampling": "gaussian"}, {"antithetic": False, "samples": 3}])
def test_one_seed_is_the_estimators_first_estimate_bit_for_bit(options):
    theta = [0.3, -1.2, 2.5]
    g = plateau_free.torch.wrap(floor_sum, sigma=0.4, **options)
    for seed in [0, 1, 12345, 2**64 - 1]:
        expected = plateau_free.PlateauFreeGradient(floor_sum, seed=seed, **options).estimate(theta, 0.4)
        assert np.array_equal(gradient(g, theta, seed), expected)
    # A seed given as an integer tensor is the same seed.
    assert np.array_equal(gradient(g, theta, torch.tensor(12345)), gradient(g, theta, 12345))


@pytest.mark.parametrize("dim, sigma", [(1, 1e-9), (1, 1e9), (1000, 0.4), (7, 1e-300)])
def test_extreme_spreads_and_dimensions_are_the_estimators(dim, sigma):
    theta = np.linspace(-3.0, 3.0, dim)
    g = plateau_free.torch.wrap(floor_sum, sigma=sigma, samples=4)
    expected = plateau_free.PlateauFreeGradient(floor_sum, seed=dim, samples=4).estimate(theta, sigma)
    assert np.array_equal(gradient(g, theta, dim), expected)


def test_a_nan_in_the_backward_pass_is_the_estimators_value_error():
    g = plateau_free.torch.wrap(lambda x: float("nan") if x[0] > 0 else 0.0, sigma=1.0, samples=64)
    theta = torch.tensor([-1.0], dtype=torch.float64, requires_grad=True)
    value = g(theta, 0)
    assert value.item() == 0.0
    with pytest.raises(ValueError, match="NaN"):
        value.backward()


def test_the_value_is_f_of_theta_in_thetas_dtype_and_the_seeds_differ():
    g = plateau_free.torch.wrap(floor_sum, sigma=0.4)
    theta = torch.tensor([0.3, -1.2, 2.5], dtype=torch.float32, requires_grad=True)
    value = g(theta, 0)
    assert value.dtype == torch.float32 and value.item() == floor_sum(np.array([0.3, -1.2, 2.5], dtype=np.float32))
    value.backward()
    assert theta.grad is not None and theta.grad.dtype == torch.float32
    assert not np.array_equal(gradient(g, [0.3, -1.2, 2.5], 0), gradient(g, [0.3, -1.2, 2.5], 1))


PIXELS = (np.arange(32) + 0.5) / 32


def render(x):
    """A 1-D "renderer": a box of half-width 0.1 centred at x[0], on 32 pixels."""
    return (np.abs(PIXELS - x[0]) < 0.1).astype(float)


def test_an_image_valued_f_under_a_linear_loss_has_the_smoothed_gradient():
    w = torch.linspace(-1.0, 2.0, 32, dtype=torch.float64)
    theta, sigma = 0.45, 0.05
    g = plateau_free.torch.wrap(render, sigma=sigma, samples=4)
    grads = []
    for seed in range(3000):
        t = torch.tensor([theta], dtype=torch.float64, requires_grad=True)
        (grad,) = torch.autograd.grad(torch.dot(w, g(t, seed)), t)
        grads.append(grad.item())
    expected = sum(
        wi * (smoothed_step_gradient(theta, p - 0.1, sigma) - smoothed_step_gradient(theta, p + 0.1, sigma))
        for wi, p in zip(w.numpy(), PIXELS)
    )
    assert_mean_matches(grads, expected, "w . image")


def test_an_image_under_a_nonlinear_loss_is_the_estimate_of_its_cotangent_bit_for_bit():
    target = torch.as_tensor(render(np.array([0.7])))
    g = plateau_free.torch.wrap(render, sigma=0.3, samples=8)
    t = torch.tensor([0.4], dtype=torch.float64, requires_grad=True)
    torch.sum((g(t, 9) - target) ** 2).backward()
    v = 2.0 * (render(np.array([0.4])) - target.numpy())
    estimator = plateau_free.PlateauFreeGradient(lambda x: float(np.vdot(v, render(x))), samples=8, seed=9)
    assert t.grad is not None and np.array_equal(t.grad.numpy(), estimator.estimate([0.4], 0.3))


def test_torch_optim_adam_minimises_a_staircase():
    # sum((floor(x) - target)^2) is flat between integers: autograd's gradient is zero.
    target = np.array([1.0, -2.0])
    g = plateau_free.torch.wrap(lambda x: float(np.sum((np.floor(x) - target) ** 2)), sigma=0.3, samples=8)
    theta = torch.tensor([-2.5, 2.5], dtype=torch.float64, requires_grad=True)
    optimizer = torch.optim.Adam([theta], lr=0.05)
    for seed in range(300):
        optimizer.zero_grad()
        g(theta, seed).backward()
        optimizer.step()
    assert np.array_equal(np.floor(theta.detach().numpy()), target), theta


def test_a_batched_f_gives_the_unbatched_estimate():
    theta = [0.3, -1.2, 2.5]
    one = gradient(plateau_free.torch.wrap(floor_sum, sigma=0.4, samples=8), theta, 5)
    batch = plateau_free.torch.wrap(lambda xs: np.sum(np.floor(xs), axis=1), sigma=0.4, samples=8, batched=True)
    np.testing.assert_allclose(gradient(batch, theta, 5), one, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize(
    "options, name",
    [
        ({"sigma": 0.0}, "sigma"),
        ({"sigma": float("inf")}, "sigma"),
        ({"sigma": None}, "sigma"),
        ({"sigma": 0.1, "samples": 5}, "samples"),
        ({"sigma": 0.1, "sampling": "sobol"}, "sampling"),
        ({"sigma": 0.1, "batched": 1}, "batched"),
    ],
)
def test_bad_options_are_value_errors_naming_them(options, name):
    with pytest.raises(ValueError, match=name):
        plateau_free.torch.wrap(floor_sum, **options)


@pytest.mark.parametrize("seed", [-1, 2**64, 1.5, "zero", True, torch.tensor([1, 2]), torch.tensor(1.0)])
def test_bad_seeds_are_value_errors_naming_the_seed(seed):
    g = plateau_free.torch.wrap(floor_sum, sigma=0.1)
    with pytest.raises(ValueError, match="seed"):
        g(torch.zeros(3, requires_grad=True), seed)


def test_bad_thetas_are_value_errors():
    g = plateau_free.torch.wrap(floor_sum, sigma=[0.1, 0.2])
    with pytest.raises(ValueError, match="sigma has 2 spreads but theta has 3"):
        g(torch.zeros(3, requires_grad=True), 0)
    with pytest.raises(ValueError, match="theta"):
        g(torch.zeros(2, dtype=torch.int64), 0)
    with pytest.raises(ValueError, match="theta"):
        g([0.0, 0.0], 0)


def test_the_modules_example_runs():
    failures, tried = doctest.testmod(plateau_free.torch, optionflags=doctest.ELLIPSIS)
    assert tried > 0 and failures == 0
