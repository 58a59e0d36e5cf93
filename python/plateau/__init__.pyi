"""Type stubs of the Python package ``plateau`` (the Rust extension ``plateau._plateau`` and
the pure-Python ``minimize``)."""

import enum
import os
from typing import Any, Callable, Literal, Optional, Sequence, SupportsFloat, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__version__: str
PAPER_SIGMA_MIN: float
PAPER_WARMUP: float

_ArrayLike = npt.ArrayLike
_FloatArray = npt.NDArray[np.float64]
_SamplingName = Union[Literal["radial", "per_coordinate", "gaussian"], "Sampling", str]
_ScheduleName = Literal["paper", "constant", "exponential", "cosine"]

class Sampling(str, enum.Enum):
    """The sampler of perturbations: ``Radial`` (default, exact in every dimension),
    ``PerCoordinate`` (the paper's; biased for non-separable f), ``Gaussian`` (plain ES)."""

    Radial = "radial"
    PerCoordinate = "per_coordinate"
    Gaussian = "gaussian"

@final
class PlateauFreeGradient:
    """The gradient of ``fun`` smoothed by a Gaussian of spread ``sigma`` in parameter space,
    estimated from ``samples`` evaluations of ``fun`` per estimate.

    ``fun(x) -> float`` (``x``: float64 array shaped like the ``x`` of ``estimate``);
    ``seeded=True``: ``fun(x, seed)`` with one seed per antithetic pair (common random
    numbers); ``batched=True``: ``fun(X) -> N values`` for ``X`` of shape ``(N, *x.shape)``,
    once per estimate; both: ``fun(X, seeds)`` with ``seeds`` a uint64 array of length N.
    ``parallel=True`` runs the evaluations of one estimate on several threads (useful when
    ``fun`` releases the GIL); results are bit-for-bit those of the sequential run.
    """

    def __new__(
        cls,
        fun: Callable[..., Any],
        samples: int = 2,
        sampling: _SamplingName = "radial",
        antithetic: bool = True,
        seed: int = 0,
        batched: bool = False,
        seeded: bool = False,
        orthogonal: bool = False,
        parallel: bool = False,
    ) -> "PlateauFreeGradient": ...
    def estimate(self, x: _ArrayLike, sigma: Union[float, _ArrayLike]) -> _FloatArray:
        """The gradient of ``fun`` smoothed by N(0, sigma^2 I) at ``x``, shaped like ``x``.
        ``sigma``: a positive float, or one positive spread per element of ``x``."""
    def reset(self) -> None:
        """The next estimate repeats the first one's draws."""
    @property
    def fun(self) -> Callable[..., Any]: ...
    @property
    def samples(self) -> int: ...
    @property
    def sampling(self) -> str: ...
    @property
    def antithetic(self) -> bool: ...
    @property
    def seed(self) -> int: ...
    @property
    def batched(self) -> bool: ...
    @property
    def seeded(self) -> bool: ...
    @property
    def orthogonal(self) -> bool: ...
    @property
    def parallel(self) -> bool: ...
    @property
    def estimates(self) -> int:
        """Estimates made since construction or the last ``reset()``."""
    @property
    def nfev(self) -> int:
        """Evaluations of ``fun`` since construction."""

@final
class FiniteDifference:
    """Central finite differences of step ``step``: the unsmoothed gradient (zero on a plateau);
    ``2 n`` evaluations per estimate."""

    def __new__(
        cls,
        fun: Callable[..., Any],
        step: float = 1e-3,
        seed: int = 0,
        batched: bool = False,
        seeded: bool = False,
    ) -> "FiniteDifference": ...
    def estimate(self, x: _ArrayLike, sigma: Optional[float] = None) -> _FloatArray: ...
    @property
    def step(self) -> float: ...
    @property
    def seed(self) -> int: ...
    @property
    def nfev(self) -> int: ...

@final
class Spsa:
    """SPSA: one Rademacher direction per estimate, perturbation size ``sigma``; 2 evaluations."""

    def __new__(
        cls, fun: Callable[..., Any], seed: int = 0, batched: bool = False, seeded: bool = False
    ) -> "Spsa": ...
    def estimate(self, x: _ArrayLike, sigma: float) -> _FloatArray: ...
    @property
    def seed(self) -> int: ...
    @property
    def nfev(self) -> int: ...

@final
class Annealer:
    """The spread sigma per iteration: ``paper`` (sigma0 for ``warmup`` of the run, then linear
    to ``sigma_min``), ``constant``, ``exponential``, ``cosine``."""

    def __new__(
        cls,
        schedule: _ScheduleName = "paper",
        sigma0: float = 0.5,
        sigma_min: float = 0.01,
        iterations: int = 400,
        warmup: float = 0.5,
    ) -> "Annealer": ...
    @staticmethod
    def paper(sigma0: float = 0.5, iterations: int = 400) -> "Annealer": ...
    @staticmethod
    def constant(sigma: float = 0.5, iterations: int = 400) -> "Annealer": ...
    @staticmethod
    def exponential(sigma0: float = 0.5, sigma_min: float = 0.01, iterations: int = 400) -> "Annealer": ...
    @staticmethod
    def cosine(sigma0: float = 0.5, sigma_min: float = 0.01, iterations: int = 400) -> "Annealer": ...
    def sigma(self, iteration: int) -> float: ...
    def sigmas(self) -> _FloatArray: ...
    @property
    def sigma0(self) -> float: ...
    @property
    def sigma_min(self) -> float: ...
    @property
    def iterations(self) -> int: ...
    @property
    def schedule(self) -> str: ...
    @property
    def warmup(self) -> Optional[float]: ...

@final
class Adam:
    """Adam with bias correction; ``bounds=(lower, upper)`` projects x after every step."""

    def __new__(
        cls,
        lr: float = 0.02,
        beta1: float = 0.9,
        beta2: float = 0.999,
        epsilon: float = 1e-8,
        bounds: Optional[Tuple[Sequence[float], Sequence[float]]] = None,
    ) -> "Adam": ...
    def step(self, x: _ArrayLike, gradient: _ArrayLike) -> _FloatArray:
        """One step downhill; returns the new x."""
    def reset(self) -> None: ...
    @property
    def lr(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def bounds(self) -> Optional[Tuple[_FloatArray, _FloatArray]]: ...

class History:
    """Per-iteration records of a run (arrays of length ``nit``)."""

    sigma: _FloatArray
    grad_norm: _FloatArray
    fun: _FloatArray
    nfev: npt.NDArray[np.uint64]
    x: Optional[_FloatArray]
    def __init__(
        self,
        sigma: _FloatArray,
        grad_norm: _FloatArray,
        fun: _FloatArray,
        nfev: npt.NDArray[np.uint64],
        x: Optional[_FloatArray] = None,
    ) -> None: ...
    def __len__(self) -> int: ...

class OptimizeResult(dict[str, Any]):
    """The fields of ``scipy.optimize.OptimizeResult``, and ``history``; with
    ``method='adaptive'`` also ``restarts`` and ``sigma`` (``history`` is then None)."""

    x: _FloatArray
    fun: float
    nit: int
    nfev: int
    success: bool
    status: int
    message: str
    history: Optional[History]
    restarts: Optional[int]
    sigma: Optional[float]
    def __getattr__(self, name: str) -> Any: ...

_Bounds = Union[
    Sequence[Tuple[Optional[SupportsFloat], Optional[SupportsFloat]]],
    Tuple[Optional[SupportsFloat], Optional[SupportsFloat]],
    Any,
]

def minimize(
    fun: Callable[..., Any],
    x0: _ArrayLike,
    *,
    budget: Optional[int] = None,
    sigma0: Optional[float] = None,
    iterations: Optional[int] = None,
    lr: Optional[float] = None,
    samples: Optional[int] = None,
    sampling: Optional[_SamplingName] = None,
    antithetic: Optional[bool] = None,
    seed: int = 0,
    bounds: Optional[_Bounds] = None,
    annealer: Union[_ScheduleName, Annealer, None] = None,
    sigma_min: Optional[float] = None,
    batched: bool = False,
    seeded: bool = False,
    callback: Optional[Callable[..., Any]] = None,
    method: Optional[Literal["adaptive", "plateau", "fd", "spsa"]] = None,
    target: Optional[float] = None,
    population: Optional[int] = None,
    restarts: bool = True,
    step: Optional[float] = None,
    orthogonal: Optional[bool] = None,
    parallel: Optional[bool] = None,
    record_x: Optional[bool] = None,
    final_evaluation: Optional[bool] = None,
    checkpoint: Union[str, os.PathLike[str], None] = None,
    checkpoint_every: Optional[int] = None,
) -> OptimizeResult:
    """Minimise ``fun`` from ``x0``. ``minimize(fun, x0, budget=...)`` runs the library's
    general-purpose search (``method='adaptive'``, the Rust ``plateau::Minimizer``; the
    default when ``budget`` is given and no option of the paper's loop is) and returns the best
    point seen; otherwise (or ``method='plateau'``) the paper's loop: the plateau-free
    gradient, Adam and an annealed sigma. ``None`` for an option of the paper's loop means its
    default (``sigma0=0.5``, ``lr=0.02``, ``samples=2``, ``sampling='radial'``,
    ``antithetic=True``, ``annealer='paper'``, ``sigma_min=0.01``, ``step=1e-3``,
    ``orthogonal=False``, ``parallel=False``, ``record_x=False``,
    ``final_evaluation=True``). ``checkpoint=path`` (the paper's loop) keeps the run's state
    in a file, written atomically every ``checkpoint_every`` iterations (default: about every
    30 s; 0: only at the end and on an exception) and when ``fun`` raises, and continues from
    it when it exists and matches the settings, bit for bit."""

__all__ = [
    "PAPER_SIGMA_MIN",
    "PAPER_WARMUP",
    "Adam",
    "Annealer",
    "FiniteDifference",
    "History",
    "OptimizeResult",
    "PlateauFreeGradient",
    "Sampling",
    "Spsa",
    "minimize",
]
