"""The plateau-free gradient inside Dr.Jit's automatic differentiation (Mitsuba 3's), for the
parameters whose AD gradient is zero or useless (``pip install "plateau-free[mitsuba]"``).

:class:`PlateauFreeOp` is a ``drjit.CustomOp`` in a callable: ``op(theta, image, sigma)``
returns ``image`` unchanged, and in the backward pass gives

- ``image`` the cotangent ``v`` it receives, unchanged, so that whatever ``image`` depends on
  through Dr.Jit (a Mitsuba render's reflectances, textures, ...) gets Mitsuba's own gradient;
- ``theta`` (the plateau-prone parameters, say an object's position whose only visible effect
  is a shadow) the plateau-free estimate of the gradient of ``E <v, render(theta + tau)>``,
  ``tau ~ N(0, sigma^2 I)``: :class:`plateau_free.PlateauFreeGradient` on the objective
  ``x -> <v, render(x)>``, from renders at perturbed ``theta``.

So one ``dr.backward(loss)`` gives both kinds of gradient, and one optimizer (``mi.ad.Adam``)
steps both::

    op = PlateauFreeOp(render, restore=scene.set_theta, samples=2, seed=0)
    image_ad = mi.render(scene, params, seed=it, spp=spp)    # theta set in the scene, detached
    image = op(opt["theta"], image_ad, sigma=annealer.sigma(it))
    loss = dr.mean(dr.square(image - reference), axis=None)
    dr.backward(loss)       # opt["theta"].grad: ours; the reflectance's: Mitsuba's

``render(x, seed)`` renders with the plateau-prone parameters at ``x`` (a float64 numpy array
shaped like ``theta``) and returns the image (anything ``numpy.asarray`` takes, the shape of
``image``); it is called ``samples`` times per backward pass with AD suspended, ``seed`` shared
by the two members of an antithetic pair (common random numbers). ``restore(theta)``, if
given, is called after them, so that Mitsuba's own backward pass, which runs after ours and
re-traces the scene, finds the parameters at ``theta`` again.

The estimate in backward pass ``k`` (counted from 0) is bit for bit
``PlateauFreeGradient(fun, samples=..., seed=..., seeded=True).estimate(theta, sigma)`` as
that estimator's ``k``-th estimate, with ``fun(x, s) = float(np.dot(v, render(x, s)))`` over
the flattened float64 arrays (:attr:`PlateauFreeOp.estimator` is that estimator).
Forward-mode AD through ``theta`` is not available (it would need a Jacobian-vector product of
the smoothed render): a forward pass with a gradient on ``theta`` raises.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Optional

# Typed by drjit itself; the ignore keeps mypy quiet where drjit is not installed.
import drjit as dr  # type: ignore[import-not-found, unused-ignore]
import numpy as np
import numpy.typing as npt

from ._native import PlateauFreeGradient
from ._types import _SamplingName

__all__ = ["PlateauFreeOp"]

_Render = Callable[[npt.NDArray[np.float64], int], Any]


class PlateauFreeOp:
    """``op(theta, image, sigma)``: ``image``, with the plateau-free gradient for ``theta`` in
    Dr.Jit's backward pass (see the module).

    Parameters
    ----------
    render:
        ``render(x, seed)`` -> the image at the plateau-prone parameters ``x``.
    restore:
        ``restore(theta)``, called after the perturbed renders of a backward pass.
    samples, sampling, antithetic, seed:
        :class:`plateau_free.PlateauFreeGradient`'s options (``seeded=True`` always).

    Raises
    ------
    ValueError
        A bad estimator option, named as :class:`plateau_free.PlateauFreeGradient` names it.
    """

    def __init__(
        self,
        render: _Render,
        *,
        restore: Optional[Callable[[npt.NDArray[np.float64]], Any]] = None,
        samples: int = 2,
        sampling: _SamplingName = "radial",
        antithetic: bool = True,
        seed: int = 0,
    ) -> None:
        self._render = render
        self._restore = restore
        self._cotangent: Optional[npt.NDArray[np.float64]] = None
        self.renders = 0
        self.estimator = PlateauFreeGradient(
            self._value, samples=samples, sampling=sampling, antithetic=antithetic, seed=seed,
            seeded=True,
        )  # fmt: skip

    def _value(self, x: npt.NDArray[np.float64], seed: int) -> float:
        """``<v, render(x, seed)>`` for the cotangent ``v`` of the backward pass under way."""
        assert self._cotangent is not None, "called outside a backward pass"
        with dr.suspend_grad():  # type: ignore[no-untyped-call]
            image = np.asarray(self._render(x, int(seed)), dtype=np.float64).ravel()
        self.renders += 1
        if image.shape != self._cotangent.shape:
            raise ValueError(
                f"render returned {image.size} values for an image of {self._cotangent.size}"
            )
        return float(np.dot(self._cotangent, image))

    def gradient(
        self, theta: npt.ArrayLike, cotangent: npt.ArrayLike, sigma: float
    ) -> npt.NDArray[np.float64]:
        """The estimate the backward pass gives ``theta`` for the cotangent ``cotangent``
        (the next of :attr:`estimator`'s estimates), then ``restore(theta)``."""
        x = np.asarray(theta, dtype=np.float64)
        self._cotangent = np.asarray(cotangent, dtype=np.float64).ravel()
        try:
            return self.estimator.estimate(x, sigma)
        finally:
            self._cotangent = None
            if self._restore is not None:
                self._restore(x)

    def __call__(self, theta: Any, image: Any, sigma: float) -> Any:
        """``image``, tied to ``theta`` in Dr.Jit's AD graph (see the module).

        Raises
        ------
        ValueError
            ``sigma`` not finite and positive.
        """
        if not (isinstance(sigma, (int, float)) and math.isfinite(sigma) and sigma > 0):
            raise ValueError(f"sigma = {sigma!r} is invalid: must be finite and > 0")
        return dr.custom(_Op, theta, image, self, float(sigma))


class _Op(dr.CustomOp):
    """The custom operation behind :class:`PlateauFreeOp`."""

    def eval(self, theta: Any, image: Any, owner: PlateauFreeOp, sigma: float) -> Any:
        self.theta, self.owner, self.sigma = theta, owner, sigma
        self.image_type = type(image)
        return type(image)(image)

    def forward(self) -> None:
        if np.any(np.asarray(self.grad_in("theta")) != 0):
            raise NotImplementedError(
                "PlateauFreeOp has no forward-mode derivative for theta: use dr.backward"
            )
        self.set_grad_out(self.grad_in("image"))

    def backward(self) -> None:
        v = self.grad_out()
        self.set_grad_in("image", v)
        grad = self.owner.gradient(np.asarray(self.theta), np.asarray(v), self.sigma)
        self.set_grad_in("theta", type(self.theta)(grad.astype(np.float32).reshape(-1)))

    def name(self) -> str:
        return "PlateauFreeOp"
