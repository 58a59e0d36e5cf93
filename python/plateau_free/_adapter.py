"""What the framework adapters (``plateau_free.jax``, ``plateau_free.torch``) share, on the host
side and in numpy: the options checked once, ``f``'s value at ``theta``, and the vector-Jacobian
product ``v . d/dtheta E f(theta + tau)`` estimated by :class:`PlateauFreeGradient` at a given
seed. The frameworks only move arrays in and out."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._native import OptionTypeError, PlateauFreeGradient
from ._checks import _is_bool, _is_real, _positive, _show, _whole
from ._types import _FloatArray, _SamplingName

_U64_MAX = 2**64 - 1


@dataclasses.dataclass(frozen=True)
class _Smoothing:
    """``f`` and the estimator's options, checked: the whole state of an adapter."""

    f: Callable[..., Any]
    sigma: Union[float, _FloatArray]
    samples: int
    sampling: str
    antithetic: bool
    orthogonal: bool
    batched: bool

    @staticmethod
    def checked(
        f: Callable[..., Any],
        sigma: Union[float, npt.ArrayLike],
        samples: int,
        sampling: _SamplingName,
        antithetic: bool,
        orthogonal: bool,
        batched: bool,
    ) -> _Smoothing:
        if not callable(f):
            raise OptionTypeError(f"f = {_show(f)} must be callable")
        for name, flag in (("antithetic", antithetic), ("orthogonal", orthogonal), ("batched", batched)):
            if not _is_bool(flag):
                raise OptionTypeError(f"{name} = {_show(flag)} must be True or False")
        # The estimator checks samples, sampling and their combinations with its own messages.
        PlateauFreeGradient(
            _never_called, samples=samples, sampling=sampling, antithetic=antithetic, orthogonal=orthogonal
        )
        return _Smoothing(
            f, _checked_sigma(sigma), int(samples), str(sampling), bool(antithetic), bool(orthogonal), bool(batched)
        )

    def check_theta(self, shape: Tuple[int, ...]) -> None:
        """A ValueError for per-coordinate spreads that do not fit ``theta`` (before any trace or
        evaluation, so that the message is not wrapped in the framework's)."""
        size = math.prod(shape)
        if isinstance(self.sigma, np.ndarray) and self.sigma.size != size:
            raise ValueError(
                f"sigma has {self.sigma.size} spreads but theta has {size} elements (shape {shape}): "
                "give one sigma, or one per element of theta"
            )

    def value(self, theta: npt.ArrayLike, shape: Optional[Tuple[int, ...]]) -> _FloatArray:
        """``f(theta)`` as a float64 array of ``shape`` (None: any), ``theta`` handed over as
        float64."""
        x = np.asarray(theta, dtype=np.float64)
        if self.batched:
            out = np.asarray(self.f(x[np.newaxis]), dtype=np.float64)
            if out.shape[:1] != (1,):
                raise ValueError(f"f (batched=True) returned shape {out.shape} for one point; expected (1, ...)")
            out = out[0]
        else:
            out = np.asarray(self.f(x), dtype=np.float64)
        if shape is not None and out.shape != shape:
            raise ValueError(f"f returned a value of shape {out.shape}; expected {shape} (the shape= given)")
        return out

    def estimator(self, v: npt.ArrayLike, seed: int) -> PlateauFreeGradient:
        """The estimator of ``d/dtheta E[v . f(theta + tau)]`` at ``seed``: its first estimate is
        :func:`vjp`. ``v . f(x)`` is ``float(np.vdot(v, f(x)))`` (``v * f(x)`` for a scalar ``f``,
        exact when ``v`` is 1: the estimate of ``f`` itself)."""
        return PlateauFreeGradient(
            _dotted(self.f, np.asarray(v, dtype=np.float64), self.batched),
            samples=self.samples,
            sampling=self.sampling,
            antithetic=self.antithetic,
            orthogonal=self.orthogonal,
            seed=seed,
            batched=self.batched,
        )

    def vjp(self, theta: npt.ArrayLike, v: npt.ArrayLike, seed: int) -> _FloatArray:
        """The plateau-free estimate of ``d/dtheta E[v . f(theta + tau)]``, ``tau ~ N(0,
        sigma^2 I)``: :class:`PlateauFreeGradient`'s first estimate with ``seed``, shaped like
        ``theta``."""
        sigma: Any = self.sigma
        return self.estimator(v, seed).estimate(np.asarray(theta, dtype=np.float64), sigma)


def _dotted(f: Callable[..., Any], v: _FloatArray, batched: bool) -> Callable[..., Any]:
    """The objective ``x -> v . f(x)`` (batched: ``X -> [v . f(x) for x in X]``)."""
    if batched:
        flat = v.reshape(-1)
        return lambda xs: np.asarray(f(xs), dtype=np.float64).reshape(len(xs), -1) @ flat
    if v.ndim == 0:
        scale = float(v)
        return lambda x: scale * float(f(x))
    return lambda x: float(np.vdot(v, np.asarray(f(x), dtype=np.float64)))


def _never_called(x: Any) -> float:
    raise AssertionError("the options check never evaluates f")  # pragma: no cover


def _checked_sigma(sigma: Any) -> Union[float, _FloatArray]:
    """``sigma``: one finite spread > 0, or an array of them (one per element of theta)."""
    if _is_real(sigma):
        return _positive("sigma", sigma)
    must = f"sigma = {_show(sigma)} must be a finite number > 0, or an array of them (one per element of theta)"
    if sigma is None or _is_bool(sigma) or isinstance(sigma, (str, bytes)):
        raise OptionTypeError(must)
    try:
        spreads = np.array(sigma, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise OptionTypeError(must) from e
    if spreads.ndim == 0:
        return _positive("sigma", float(spreads))
    if spreads.size == 0 or not (np.all(np.isfinite(spreads)) and np.all(spreads > 0)):
        raise ValueError(must)
    return spreads.reshape(-1)


def _checked_seed(seed: Any) -> int:
    """A seed for the estimator: a whole number from 0 to 2**64 - 1."""
    return _whole("seed", seed, 0, _U64_MAX)
