"""Type stubs of the Rust extension module ``plateau_free._native``; its public names are
re-exported by ``plateau_free`` (whose own modules, ``__init__.py``, ``_minimize.py``, ..., are
typed inline)."""

import os
from typing import Any, Callable, Literal, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__version__: str
PAPER_SIGMA_MIN: float
PAPER_WARMUP: float
STALL_WINDOW: float
DEFAULT_POLISH: float
CHECKPOINT_SECONDS: float
PROGRESS_SECONDS: float

_ArrayLike = npt.ArrayLike
_FloatArray = npt.NDArray[np.float64]
# ``plateau_free.Sampling`` is a ``str``: its members are accepted too.
_SamplingName = Union[Literal["radial", "per_coordinate", "gaussian"], str]
_ScheduleName = Literal["paper", "constant", "exponential", "cosine"]

class OptionTypeError(ValueError, TypeError):
    """An option of the wrong type: a ValueError, as every bad option, and a TypeError."""

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

    One estimator may be shared by threads: their estimates run one at a time (each draws the
    numbers of its place in that order).
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

__all__ = [
    "Adam",
    "Annealer",
    "CHECKPOINT_SECONDS",
    "DEFAULT_POLISH",
    "FiniteDifference",
    "OptionTypeError",
    "PAPER_SIGMA_MIN",
    "PAPER_WARMUP",
    "PROGRESS_SECONDS",
    "PlateauFreeGradient",
    "STALL_WINDOW",
    "Spsa",
    "_AskTell",
    "_drive",
    "_replace_file",
    "_rust_reference_estimates",
    "_rust_reference_minimize",
    "_rust_reference_minimize_adaptive",
    "_rust_seconds_per_evaluation",
]

# The options of ``method='adaptive'`` and ``'polished'``: the dict that
# ``plateau_free._options._adaptive_options`` makes, read key by key by ``AdaptiveOptions`` in
# python/src/convert.rs (declared there and in the options' table alone).
_AdaptiveOptions = dict[str, Any]

class _AskTell:
    """The Rust side of ``plateau_free.AskTell``: an adaptive or paper-loop run, asked and told."""

    @staticmethod
    def adaptive(x0: Any, options: _AdaptiveOptions) -> _AskTell: ...
    @staticmethod
    def paper(
        x0: Any,
        adam: Adam,
        annealer: Annealer,
        iterations: int,
        samples: int = 2,
        sampling: str = "radial",
        antithetic: bool = True,
        orthogonal: bool = False,
        seed: int = 0,
        record_x: bool = False,
        final_evaluation: bool = True,
        keep_history: int | None = None,
        on_failure: str = "raise",
    ) -> _AskTell: ...
    @staticmethod
    def baseline(
        x0: Any,
        adam: Adam,
        annealer: Annealer,
        iterations: int,
        baseline: Literal["fd", "spsa"],
        step: float = 1e-3,
        seed: int = 0,
        record_x: bool = False,
        final_evaluation: bool = True,
        keep_history: int | None = None,
    ) -> _AskTell: ...
    def _state(self) -> str: ...
    @staticmethod
    def _from_state(state: str) -> _AskTell: ...
    def __reduce__(self) -> tuple[Any, tuple[str]]: ...
    def ask(self) -> tuple[Any, Any] | None: ...
    def tell(self, values: list[float]) -> None: ...
    @property
    def done(self) -> bool: ...
    @property
    def nfev(self) -> int: ...
    @property
    def nit(self) -> int: ...
    @property
    def final_asked(self) -> bool: ...
    def best(self) -> tuple[Any, float] | None: ...
    def sigma(self) -> float: ...
    def last_step(self) -> tuple[int, Any, float, float, Any, int] | None: ...
    def partial(self) -> dict[str, Any] | None: ...
    def result(self) -> dict[str, Any] | None: ...

class _LeastSquares:
    """The Rust side of ``plateau_free.least_squares``: a ``LeastSquaresAskTell`` run, driven
    by :func:`_drive`."""

    def __init__(
        self,
        x0: list[float],
        outputs: int,
        sparsity: list[tuple[int, int]] | None,
        budget: int,
        sigma0: float,
        pairs: int,
        memory: int,
        damping: float,
        max_step: float,
        acceptance_name: str,
        smoothed_residuals: bool,
        bounds: tuple[list[float], list[float]] | None,
        seed: int,
        on_failure: str = "continue",
    ) -> None: ...
    def ask(self) -> tuple[Any, Any] | None: ...
    def tell(self, outputs: list[float]) -> None: ...
    @property
    def evaluations(self) -> int: ...
    @property
    def done(self) -> bool: ...
    def result(self) -> tuple[list[float], float, list[float], int, int, int]: ...

def _rust_reference_estimates(
    x: Any,
    sigma: float,
    samples: int = 2,
    sampling: str = "radial",
    antithetic: bool = True,
    seed: int = 0,
    count: int = 1,
    seeded: bool = False,
    orthogonal: bool = False,
) -> Any: ...
def _rust_reference_minimize(
    x0: Any,
    sigma0: float = 0.5,
    iterations: int = 50,
    lr: float = 0.02,
    samples: int = 2,
    seed: int = 0,
) -> Any: ...
def _rust_reference_minimize_adaptive(
    x0: Any,
    budget: int | None = None,
    seed: int = 0,
    sigma0: float | None = None,
    bounds: tuple[list[float], list[float]] | None = None,
    seeded: bool = False,
    paper: tuple[int, float, float] | None = None,
    polish: float | None = None,
) -> dict[str, Any]: ...
def _replace_file(path: str, data: bytes) -> None: ...
def _drive(
    run: Union[_AskTell, _LeastSquares],
    evaluate: Callable[[Any, Any], Any],
    *,
    disp: bool = False,
    keep: int = 1_000_000,
    checkpoint: Union[str, "os.PathLike[str]", None] = None,
    checkpoint_every: Optional[int] = None,
    settings: Sequence[Tuple[str, str]] = ...,
    after: Optional[Callable[[int, int, Any], Any]] = None,
) -> dict[str, Any]: ...
def _rust_seconds_per_evaluation(dim: int = 10, samples: int = 10000, repeats: int = 5) -> float: ...
