"""JAX: a black-box renderer inside a jitted pipeline, differentiated by plateau_free.jax.

    python python/examples/jax_pipeline.py      # needs pip install "plateau-free[jax]"

`render` draws a box centred at theta on 32 pixels: flat in theta almost everywhere, and at the
start the box misses the target's, so the exact gradient is zero. `plateau_free.jax.wrap`
gives `jax.grad` the gradient of the Gaussian-smoothed pipeline instead.
"""

import jax
import jax.numpy as jnp
import numpy as np

import plateau_free.jax

pixels = (np.arange(32) + 0.5) / 32


def render(x):  # a black box on the host: one image per x
    return (np.abs(pixels - x[0]) < 0.1).astype(float)


target = jnp.asarray(render([0.7]))
g = plateau_free.jax.wrap(render, sigma=0.25, samples=16, shape=(32,))


@jax.jit
def step(theta, key):
    loss, grad = jax.value_and_grad(lambda t: jnp.mean((g(t, key) - target) ** 2))(theta)
    return theta - 0.05 * grad, loss


theta = jnp.array([0.2])
for i in range(300):
    theta, loss = step(theta, jax.random.fold_in(jax.random.key(0), i))
print("JAX:", theta, loss)  # theta about 0.7, loss 0
assert abs(float(theta[0]) - 0.7) < 0.03
