"""A black-box ``f`` as a JAX function whose gradient is the plateau-free estimate.

    >>> import jax, jax.numpy as jnp, numpy as np, plateau_free.jax
    >>> step = plateau_free.jax.wrap(lambda x: float(x[0] > 0.3), sigma=0.5, samples=64)
    >>> theta = jnp.array([0.0])
    >>> float(step(theta, jax.random.key(0)))     # f(theta) itself
    0.0
    >>> keys = jax.random.split(jax.random.key(1), 100)
    >>> grads = jax.vmap(jax.grad(step), in_axes=(None, 0))(theta, keys)  # one estimate per key
    >>> round(float(np.mean(grads)), 1)  # d/dtheta Phi((theta - 0.3) / 0.5) = 0.666
    0.7

:func:`wrap` ``(f, sigma=...)`` returns ``g(theta, key)``: its value is ``f(theta)``, its
vector-Jacobian product with a cotangent ``v`` the estimate of ``d/dtheta E[v . f(theta + tau)]``,
``tau ~ N(0, sigma^2 I)``, by :class:`plateau_free.PlateauFreeGradient` (a ``jax.custom_vjp``;
``f`` runs on the host through ``jax.pure_callback``, so ``g`` works under ``jax.jit``,
``jax.grad`` and ``jax.vmap``). ``f`` may return an array (an image; give its ``shape``): then
``loss(g(theta, key))`` with any differentiable ``loss`` gets the estimate for the cotangent
``d loss / d f``, from the same perturbed evaluations of ``f``.

The randomness is the key's: the estimate is the estimator's first with the seed
:func:`seed_of` ``(key)``: ``bits = jax.random.bits(key, (2,), jnp.uint32)``, ``seed =
bits[0] * 2**32 + bits[1]``. One key gives the same estimate every time, two keys two
independent ones. ``f`` gets float64 arrays; ``g``'s value and gradient have ``theta``'s
dtype (enable ``jax_enable_x64`` for float64 end to end).

JAX is imported when :func:`wrap` is first called: ``import plateau_free.jax`` works without it.
"""

from __future__ import annotations

import importlib
from typing import Any, Callable, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._adapter import _Smoothing
from ._native import OptionTypeError
from ._checks import _show
from ._types import _SamplingName


def wrap(
    f: Callable[..., Any],
    *,
    sigma: Union[float, npt.ArrayLike],
    samples: int = 2,
    sampling: _SamplingName = "radial",
    antithetic: bool = True,
    orthogonal: bool = False,
    batched: bool = False,
    shape: Tuple[int, ...] = (),
) -> Callable[[Any, Any], Any]:
    """``g(theta, key)``: ``f(theta)``, differentiable by the plateau-free estimate.

    Parameters
    ----------
    f : callable
        ``f(x)`` for a float64 array ``x`` shaped like ``theta``: a number, or an array of
        ``shape``. ``batched=True``: ``f(X)`` for ``X`` of shape ``(N, *theta.shape)``, returning
        ``(N, *shape)`` (one call per estimate).
    sigma : float or array
        The smoothing spread: one, or one per element of ``theta``.
    samples, sampling, antithetic, orthogonal
        As for :class:`plateau_free.PlateauFreeGradient` (the library's defaults).
    shape : tuple of int
        The shape of ``f``'s value (``()``: a number).

    Returns
    -------
    callable
        ``g(theta, key)`` with ``theta`` a floating JAX array and ``key`` a JAX PRNG key
        (``jax.random.key`` or ``jax.random.PRNGKey``).

    Raises
    ------
    ValueError
        A bad option, naming it and its value (at once); per-coordinate ``sigma`` that does not
        fit ``theta`` (when ``g`` is called).
    """
    jax = _import_jax()
    smoothing = _Smoothing.checked(f, sigma, samples, sampling, antithetic, orthogonal, batched)
    out_shape = _checked_shape(shape)
    jnp = jax.numpy

    def host_value(theta: Any) -> Any:
        return smoothing.value(theta, out_shape).astype(theta.dtype)

    def host_vjp(theta: Any, v: Any, bits: Any) -> Any:
        return smoothing.vjp(theta, v, _seed_from_bits(bits)).astype(theta.dtype)

    def value(theta: Any) -> Any:
        result = jax.ShapeDtypeStruct(out_shape, theta.dtype)
        return jax.pure_callback(host_value, result, theta, vmap_method="sequential")

    def primal(theta: Any, key: Any) -> Any:
        return value(theta)

    g: Any = jax.custom_vjp(primal)

    def g_forward(theta: Any, key: Any) -> Any:
        return value(theta), (theta, key)

    def g_backward(residuals: Any, v: Any) -> Any:
        theta, key = residuals
        bits = jax.random.bits(key, (2,), jnp.uint32)
        result = jax.ShapeDtypeStruct(theta.shape, theta.dtype)
        grad = jax.pure_callback(host_vjp, result, theta, v, bits, vmap_method="sequential")
        # The key is not differentiable: no cotangent.
        return grad, None

    g.defvjp(g_forward, g_backward)

    def checked_g(theta: Any, key: Any) -> Any:
        theta = jnp.asarray(theta)
        if not jnp.issubdtype(theta.dtype, jnp.floating):
            raise OptionTypeError(f"theta must be a floating array, not {theta.dtype}")
        smoothing.check_theta(tuple(theta.shape))
        _check_key(jax, key)
        return g(theta, key)

    return checked_g


def seed_of(key: Any) -> int:
    """The seed of the estimate that ``g(theta, key)`` differentiates with: ``bits[0] * 2**32 +
    bits[1]`` for ``bits = jax.random.bits(key, (2,), jnp.uint32)`` (a concrete key)."""
    jax = _import_jax()
    return _seed_from_bits(np.asarray(jax.random.bits(key, (2,), jax.numpy.uint32)))


def _seed_from_bits(bits: Any) -> int:
    high, low = (int(b) for b in np.asarray(bits, dtype=np.uint64).reshape(2))
    return (high << 32) | low


def _check_key(jax: Any, key: Any) -> None:
    """An OptionTypeError unless ``key`` is one PRNG key: typed (``jax.random.key``) or raw
    (``jax.random.PRNGKey``, two uint32 words); checked before the backward pass needs it."""
    dtype, shape = getattr(key, "dtype", None), tuple(getattr(key, "shape", (None,)))
    typed = dtype is not None and jax.dtypes.issubdtype(dtype, jax.dtypes.prng_key) and shape == ()
    raw = dtype == np.uint32 and shape == (2,)
    if not (typed or raw):
        given = _show(key) if dtype is None else f"an array of shape {shape} and dtype {dtype}"
        raise OptionTypeError(
            f"key = {given} must be one JAX PRNG key: jax.random.key(seed) or jax.random.PRNGKey(seed)"
        )


def _checked_shape(shape: Any) -> Tuple[int, ...]:
    must = f"shape = {_show(shape)} must be a tuple of whole numbers >= 0 (the shape of f's value)"
    if not isinstance(shape, (tuple, list)):
        raise OptionTypeError(must)
    if not all(isinstance(d, (int, np.integer)) and not isinstance(d, bool) and d >= 0 for d in shape):
        raise ValueError(must)
    return tuple(int(d) for d in shape)


def _import_jax() -> Any:
    try:
        return importlib.import_module("jax")
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            'plateau_free.jax needs JAX: pip install "plateau-free[jax]" (or the pinned jax of python/requirements-test.txt)'
        ) from e
