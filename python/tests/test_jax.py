"""plateau_free.jax.wrap: a black box as a JAX function whose vector-Jacobian product is the
plateau-free estimate. The gradient averaged over many keys is the analytic gradient of the
Gaussian-smoothed step and staircase (within 4 standard errors computed from the samples); for
one key it is bit for bit PlateauFreeGradient's first estimate with seed_of(key); jit, vmap,
image-valued f under a differentiable loss, and a pipeline loss(h(theta)) with a plateau-ridden
renderer h optimised end to end by plain gradient steps. JAX is a test requirement
(python/requirements-test.txt): these tests fail, never skip, when it is missing."""

from __future__ import annotations

import doctest
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import plateau_free
import plateau_free.jax
from helpers import assert_mean_matches, floor_sum, smoothed_floor_gradient, smoothed_step_gradient

# float64 end to end, so that the gradient is the estimator's float64 result unchanged.
jax.config.update("jax_enable_x64", True)


def step_at(a):
    return lambda x: float(x[0] > a)


def keys(count, seed=0):
    return jax.random.split(jax.random.key(seed), count)


def per_key_gradients(g, theta, count):
    """jax.grad of g at theta for `count` keys at once (vmap over the keys)."""
    return np.asarray(jax.vmap(jax.grad(g), in_axes=(None, 0))(theta, keys(count)))


@pytest.mark.parametrize("theta, a, sigma", [(0.0, 0.3, 0.5), (1.0, 0.2, 0.1), (-3.0, 2.0, 4.0)])
def test_the_mean_over_keys_is_the_smoothed_step_gradient(theta, a, sigma):
    g = plateau_free.jax.wrap(step_at(a), sigma=sigma)
    grads = per_key_gradients(g, jnp.array([theta]), 4000)
    assert_mean_matches(grads[:, 0], smoothed_step_gradient(theta, a, sigma), "step")


@pytest.mark.parametrize("sampling", ["radial", "per_coordinate", "gaussian"])
def test_the_mean_over_keys_is_the_smoothed_staircase_gradient(sampling):
    theta, sigma = np.array([0.3, -1.2, 2.5]), 0.4
    g = plateau_free.jax.wrap(floor_sum, sigma=sigma, samples=8, sampling=sampling)
    grads = per_key_gradients(g, jnp.asarray(theta), 3000)
    expected = [smoothed_floor_gradient(t, sigma) for t in theta]
    assert_mean_matches(grads, expected, f"staircase, {sampling}")


@pytest.mark.parametrize("options", [{}, {"samples": 6, "sampling": "gaussian"}, {"antithetic": False, "samples": 3}])
def test_one_key_is_the_estimators_first_estimate_with_its_seed_bit_for_bit(options):
    theta, sigma = jnp.array([0.3, -1.2, 2.5]), 0.4
    g = plateau_free.jax.wrap(floor_sum, sigma=sigma, **options)
    for key in keys(5, seed=7):
        seed = plateau_free.jax.seed_of(key)
        expected = plateau_free.PlateauFreeGradient(floor_sum, seed=seed, **options).estimate(np.asarray(theta), sigma)
        assert np.array_equal(np.asarray(jax.grad(g)(theta, key)), expected)
        assert np.array_equal(np.asarray(jax.jit(jax.grad(g))(theta, key)), expected)


@pytest.mark.parametrize("dim, sigma", [(1, 1e-9), (1, 1e9), (1000, 0.4), (7, 1e-300)])
def test_extreme_spreads_and_dimensions_are_the_estimators(dim, sigma):
    theta = jnp.linspace(-3.0, 3.0, dim)
    g = plateau_free.jax.wrap(floor_sum, sigma=sigma, samples=4)
    key = jax.random.key(dim)
    expected = plateau_free.PlateauFreeGradient(floor_sum, seed=plateau_free.jax.seed_of(key), samples=4).estimate(
        np.asarray(theta), sigma
    )
    assert np.array_equal(np.asarray(jax.jit(jax.grad(g))(theta, key)), expected)


def test_a_nan_in_the_backward_pass_is_the_estimators_value_error():
    g = plateau_free.jax.wrap(lambda x: float("nan") if x[0] > 0 else 0.0, sigma=1.0, samples=64)
    assert float(g(jnp.array([-1.0]), jax.random.key(0))) == 0.0
    with pytest.raises(Exception, match="NaN"):
        jax.block_until_ready(jax.grad(g)(jnp.array([-1.0]), jax.random.key(0)))


def test_the_seed_is_the_keys_two_random_words():
    key = jax.random.key(3)
    bits = np.asarray(jax.random.bits(key, (2,), jnp.uint32))
    assert plateau_free.jax.seed_of(key) == int(bits[0]) * 2**32 + int(bits[1])
    # The raw uint32 keys of jax.random.PRNGKey give their own seeds too.
    raw = jax.random.PRNGKey(3)
    assert plateau_free.jax.seed_of(raw) == plateau_free.jax.seed_of(jax.random.wrap_key_data(raw))
    g, theta = plateau_free.jax.wrap(floor_sum, sigma=0.4), jnp.array([0.3, -1.2, 2.5])
    assert np.array_equal(np.asarray(jax.grad(g)(theta, raw)), np.asarray(jax.grad(g)(theta, jax.random.wrap_key_data(raw))))


def test_one_key_repeats_its_estimate_and_two_keys_differ():
    g = plateau_free.jax.wrap(floor_sum, sigma=0.4)
    theta = jnp.array([0.3, -1.2, 2.5])
    k1, k2 = keys(2)
    first = np.asarray(jax.grad(g)(theta, k1))
    assert np.array_equal(first, np.asarray(jax.grad(g)(theta, k1)))
    assert not np.array_equal(first, np.asarray(jax.grad(g)(theta, k2)))


def test_the_value_is_f_of_theta_under_jit_and_vmap():
    g = plateau_free.jax.wrap(floor_sum, sigma=0.4)
    thetas = jnp.array([[0.3, -1.2, 2.5], [1.5, 1.5, -0.5]])
    assert float(g(thetas[0], jax.random.key(0))) == floor_sum(np.asarray(thetas[0]))
    assert float(jax.jit(g)(thetas[1], jax.random.key(0))) == floor_sum(np.asarray(thetas[1]))
    values = jax.vmap(g, in_axes=(0, None))(thetas, jax.random.key(0))
    assert np.array_equal(np.asarray(values), [0.0, 1.0])


def test_vmap_over_thetas_and_keys_is_the_loop_of_single_calls():
    g = plateau_free.jax.wrap(floor_sum, sigma=0.4, samples=4)
    thetas = jnp.array([[0.3, -1.2, 2.5], [1.5, 1.5, -0.5], [0.0, 0.0, 0.0]])
    ks = keys(3, seed=11)
    batched = np.asarray(jax.jit(jax.vmap(jax.grad(g)))(thetas, ks))
    for i in range(3):
        assert np.array_equal(batched[i], np.asarray(jax.grad(g)(thetas[i], ks[i])))


def test_a_batched_f_gives_the_unbatched_estimate():
    def batch(xs):
        return np.sum(np.floor(xs), axis=1)

    theta, key = jnp.array([0.3, -1.2, 2.5]), jax.random.key(5)
    one = np.asarray(jax.grad(plateau_free.jax.wrap(floor_sum, sigma=0.4, samples=8))(theta, key))
    many = np.asarray(jax.grad(plateau_free.jax.wrap(batch, sigma=0.4, samples=8, batched=True))(theta, key))
    np.testing.assert_allclose(many, one, rtol=1e-12, atol=1e-12)


def test_per_coordinate_spreads():
    sigma = np.array([0.2, 0.5, 1.0])
    theta = np.array([0.3, -1.2, 2.5])
    g = plateau_free.jax.wrap(floor_sum, sigma=sigma, samples=8)
    grads = per_key_gradients(g, jnp.asarray(theta), 3000)
    expected = [smoothed_floor_gradient(t, s) for t, s in zip(theta, sigma)]
    assert_mean_matches(grads, expected, "per-coordinate sigma")


def test_float32_theta_gives_float32_results_from_the_same_estimate():
    g = plateau_free.jax.wrap(floor_sum, sigma=0.4)
    theta, key = jnp.array([0.3, -1.2, 2.5], dtype=jnp.float32), jax.random.key(2)
    grad = jax.grad(g)(theta, key)
    assert grad.dtype == jnp.float32 and g(theta, key).dtype == jnp.float32
    seed = plateau_free.jax.seed_of(key)
    expected = plateau_free.PlateauFreeGradient(floor_sum, seed=seed).estimate(np.asarray(theta, dtype=np.float64), 0.4)
    np.testing.assert_allclose(np.asarray(grad), expected, rtol=1e-6)


# An image-valued f: a 1-D "renderer" of a box of half-width 0.1 centred at theta[0] on 32
# pixels. Every pixel is a step in theta, so the image is flat in theta almost everywhere.
PIXELS = (np.arange(32) + 0.5) / 32


def render(x):
    return (np.abs(PIXELS - x[0]) < 0.1).astype(float)


def test_an_image_valued_f_under_a_linear_loss_has_the_smoothed_gradient():
    # loss = w . image: the gradient of E[w . render(theta + tau)] is the sum over pixels of
    # w_i times the smoothed gradient of pixel i, a box: a step up at p - 0.1, down at p + 0.1.
    w = np.linspace(-1.0, 2.0, 32)
    theta, sigma = 0.45, 0.05
    g = plateau_free.jax.wrap(render, sigma=sigma, samples=4, shape=(32,))

    def loss(t, key):
        return jnp.dot(jnp.asarray(w), g(t, key))

    grads = per_key_gradients(loss, jnp.array([theta]), 3000)
    expected = sum(
        wi * (smoothed_step_gradient(theta, p - 0.1, sigma) - smoothed_step_gradient(theta, p + 0.1, sigma))
        for wi, p in zip(w, PIXELS)
    )
    assert_mean_matches(grads[:, 0], expected, "w . image")


def test_an_image_under_a_nonlinear_loss_is_the_estimate_of_its_cotangent_bit_for_bit():
    target = render(np.array([0.7]))
    g = plateau_free.jax.wrap(render, sigma=0.3, samples=8, shape=(32,))

    def loss(t, key):
        return jnp.sum((g(t, key) - target) ** 2)

    theta, key = jnp.array([0.4]), jax.random.key(9)
    v = 2.0 * (render(np.asarray(theta)) - target)  # d loss / d image at render(theta)
    estimator = plateau_free.PlateauFreeGradient(
        lambda x: float(np.vdot(v, render(x))), samples=8, seed=plateau_free.jax.seed_of(key)
    )
    assert np.array_equal(np.asarray(jax.jit(jax.grad(loss))(theta, key)), estimator.estimate(np.asarray(theta), 0.3))


@pytest.mark.parametrize("run", [1, 2, 3])
def test_a_pipeline_through_a_plateau_ridden_renderer_is_optimised_end_to_end(run):
    # loss(render(theta)), loss the mean squared error to a target image: at the start the box
    # does not overlap the target's, so the exact gradient is zero (and moving theta a little
    # changes nothing); the smoothed one leads to the target, by plain gradient steps.
    target = render(np.array([0.7]))
    exact = jax.grad(lambda t: jnp.mean(((jnp.abs(PIXELS - t[0]) < 0.1).astype(float) - target) ** 2))
    assert float(exact(jnp.array([0.2]))[0]) == 0.0
    g = plateau_free.jax.wrap(render, sigma=0.25, samples=16, shape=(32,))

    @jax.jit
    def step(theta, i):
        key = jax.random.fold_in(jax.random.key(run), i)  # a new key, so a new estimate, each step
        loss, grad = jax.value_and_grad(lambda t: jnp.mean((g(t, key) - target) ** 2))(theta)
        return theta - 0.05 * grad, loss

    theta, first = jnp.array([0.2]), None
    for i in range(300):
        theta, loss = step(theta, i)
        first = loss if first is None else first
    assert float(first) == 14 / 32  # 7 lit pixels each, none shared
    assert abs(float(theta[0]) - 0.7) < 0.03, float(theta[0])
    assert float(jnp.mean((jnp.asarray(render(np.asarray(theta))) - target) ** 2)) == 0.0


@pytest.mark.parametrize(
    "options, name",
    [
        ({"sigma": -1.0}, "sigma"),
        ({"sigma": float("nan")}, "sigma"),
        ({"sigma": [0.1, 0.0]}, "sigma"),
        ({"sigma": "wide"}, "sigma"),
        ({"sigma": 0.1, "samples": 3}, "samples"),
        ({"sigma": 0.1, "samples": 0}, "samples"),
        ({"sigma": 0.1, "sampling": "uniform"}, "sampling"),
        ({"sigma": 0.1, "antithetic": "yes"}, "antithetic"),
        ({"sigma": 0.1, "shape": "image"}, "shape"),
        ({"sigma": 0.1, "shape": (32, -1)}, "shape"),
    ],
)
def test_bad_options_are_value_errors_naming_them(options, name):
    with pytest.raises(ValueError, match=name):
        plateau_free.jax.wrap(floor_sum, **options)


def test_bad_calls_are_value_errors():
    with pytest.raises(ValueError, match="f = 3"):
        plateau_free.jax.wrap(3, sigma=0.1)
    g = plateau_free.jax.wrap(floor_sum, sigma=[0.1, 0.2])
    with pytest.raises(ValueError, match="sigma has 2 spreads but theta has 3"):
        g(jnp.zeros(3), jax.random.key(0))
    for key in [0, jnp.arange(2), keys(2), jnp.zeros(3, dtype=jnp.uint32)]:
        with pytest.raises(ValueError, match="key = .* must be one JAX PRNG key"):
            plateau_free.jax.wrap(floor_sum, sigma=0.1)(jnp.zeros(3), key)
    with pytest.raises(ValueError, match="theta must be a floating array"):
        plateau_free.jax.wrap(floor_sum, sigma=0.1)(jnp.zeros(3, dtype=jnp.int32), jax.random.key(0))
    # f's value of another shape than declared: the callback's ValueError, inside JAX's error.
    with pytest.raises(Exception, match=r"f returned a value of shape \(32,\); expected \(\)"):
        jax.block_until_ready(plateau_free.jax.wrap(render, sigma=0.1)(jnp.zeros(1), jax.random.key(0)))


def test_plateau_free_imports_no_framework_until_an_adapter_is_used():
    code = (
        "import sys, plateau_free, plateau_free.jax, plateau_free.torch, plateau_free.scipy\n"
        "print(sorted(m for m in ('jax', 'torch', 'scipy') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_the_modules_example_runs():
    failures, tried = doctest.testmod(plateau_free.jax, optionflags=doctest.ELLIPSIS)
    assert tried > 0 and failures == 0
