"""A black-box ``f`` as a PyTorch function whose gradient is the plateau-free estimate.

    >>> import torch, plateau_free.torch
    >>> step = plateau_free.torch.wrap(lambda x: float(x[0] > 0.3), sigma=0.5, samples=64)
    >>> theta = torch.zeros(1, dtype=torch.float64, requires_grad=True)
    >>> step(theta, 0)                             # f(theta) itself
    tensor(0., dtype=torch.float64, grad_fn=<PlateauFreeBackward>)
    >>> grads = [torch.autograd.grad(step(theta, seed), theta)[0] for seed in range(100)]
    >>> round(float(torch.stack(grads).mean()), 1)  # d/dtheta Phi((theta - 0.3) / 0.5) = 0.666
    0.7

:func:`wrap` ``(f, sigma=...)`` returns ``g(theta, seed)``, a ``torch.autograd.Function``
applied: its value is ``f(theta)``, its backward with the incoming gradient ``v`` the estimate
of ``d/dtheta E[v . f(theta + tau)]``, ``tau ~ N(0, sigma^2 I)``, by
:class:`plateau_free.PlateauFreeGradient` with ``seed`` (its first estimate: bit for bit
``PlateauFreeGradient(lambda x: v . f(x), seed=seed).estimate(theta, sigma)``). ``f`` may
return an array (an image): ``loss(g(theta, seed))`` with any differentiable ``loss`` works,
and so does a ``torch.optim`` optimiser::

    theta = torch.tensor([2.7, -1.4], dtype=torch.float64, requires_grad=True)
    opt = torch.optim.Adam([theta], lr=0.05)
    for seed in range(200):
        opt.zero_grad()
        g(theta, seed).backward()
        opt.step()

``f`` gets float64 numpy arrays (``theta`` is moved to the CPU); the value and gradient have
``theta``'s dtype and device.

PyTorch is imported when :func:`wrap` is first called: ``import plateau_free.torch`` works
without it.
"""

from __future__ import annotations

import importlib
from typing import Any, Callable, Union

import numpy as np
import numpy.typing as npt

from ._adapter import _checked_seed, _Smoothing
from ._native import OptionTypeError
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
) -> Callable[[Any, Any], Any]:
    """``g(theta, seed)``: ``f(theta)``, differentiable by the plateau-free estimate.

    Parameters
    ----------
    f : callable
        ``f(x)`` for a float64 array ``x`` shaped like ``theta``: a number or an array.
        ``batched=True``: ``f(X)`` for ``X`` of shape ``(N, *theta.shape)``, returning
        ``(N, ...)`` (one call per estimate).
    sigma : float or array
        The smoothing spread: one, or one per element of ``theta``.
    samples, sampling, antithetic, orthogonal
        As for :class:`plateau_free.PlateauFreeGradient` (the library's defaults).

    Returns
    -------
    callable
        ``g(theta, seed)`` with ``theta`` a floating tensor and ``seed`` a whole number from 0
        to 2**64 - 1 (an int, or an integer tensor of one element).

    Raises
    ------
    ValueError
        A bad option, naming it and its value (at once); a bad ``seed`` or ``theta``, or
        per-coordinate ``sigma`` that does not fit ``theta`` (when ``g`` is called).
    """
    torch = _import_torch()
    smoothing = _Smoothing.checked(f, sigma, samples, sampling, antithetic, orthogonal, batched)

    def forward(ctx: Any, theta: Any, seed: int) -> Any:
        ctx.save_for_backward(theta)
        ctx.seed = seed
        x = theta.detach().cpu().numpy()
        out = np.asarray(smoothing.value(x, None), dtype=np.float64)
        return torch.as_tensor(out, dtype=theta.dtype, device=theta.device)

    def backward(ctx: Any, v: Any) -> Any:
        (theta,) = ctx.saved_tensors
        x = theta.detach().cpu().numpy()
        grad = smoothing.vjp(x, v.detach().cpu().numpy(), ctx.seed)
        return torch.as_tensor(grad, dtype=theta.dtype, device=theta.device), None

    # A class made at run time: torch is imported here, not when this module is.
    function: Any = type(
        "PlateauFree",
        (torch.autograd.Function,),
        {"forward": staticmethod(forward), "backward": staticmethod(backward), "__module__": __name__},
    )

    def g(theta: Any, seed: Any) -> Any:
        if not (isinstance(theta, torch.Tensor) and theta.is_floating_point()):
            raise OptionTypeError(f"theta = {theta!r:.80} must be a floating torch.Tensor")
        if isinstance(seed, torch.Tensor):
            if seed.numel() != 1 or seed.is_floating_point() or seed.is_complex():
                raise OptionTypeError(f"seed = {seed!r:.80} must be a whole number or an integer tensor of one element")
            seed = int(seed.item())
        smoothing.check_theta(tuple(theta.shape))
        return function.apply(theta, _checked_seed(seed))

    return g


def _import_torch() -> Any:
    try:
        return importlib.import_module("torch")
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            'plateau_free.torch needs PyTorch: pip install "plateau-free[torch]" (or the pinned torch of python/requirements-test.txt)'
        ) from e
