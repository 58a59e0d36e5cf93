"""The Rust extension module; its public names are re-exported by ``plateau``."""

from typing import Any

from plateau import PAPER_SIGMA_MIN as PAPER_SIGMA_MIN
from plateau import PAPER_WARMUP as PAPER_WARMUP
from plateau import Adam as Adam
from plateau import Annealer as Annealer
from plateau import FiniteDifference as FiniteDifference
from plateau import PlateauFreeGradient as PlateauFreeGradient
from plateau import Spsa as Spsa

__all__ = [
    "Adam",
    "Annealer",
    "FiniteDifference",
    "PAPER_SIGMA_MIN",
    "PAPER_WARMUP",
    "PlateauFreeGradient",
    "Spsa",
    "_minimize",
    "_minimize_adaptive",
    "_rust_reference_estimates",
    "_rust_reference_minimize",
    "_rust_reference_minimize_adaptive",
    "_rust_seconds_per_evaluation",
]

def _minimize(
    estimator: Any,
    x0: Any,
    adam: Adam,
    annealer: Annealer,
    iterations: int | None = None,
    callback: Any = None,
    record_x: bool = False,
    checkpoint: str | None = None,
    checkpoint_every: int | None = None,
    settings: str | None = None,
) -> dict[str, Any]: ...
def _minimize_adaptive(
    fun: Any,
    x0: Any,
    budget: int | None = None,
    seed: int = 0,
    sigma0: float | None = None,
    bounds: tuple[list[float], list[float]] | None = None,
    target: float | None = None,
    population: int | None = None,
    restarts: bool = True,
    batched: bool = False,
    seeded: bool = False,
    callback: Any = None,
) -> dict[str, Any]: ...
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
) -> dict[str, Any]: ...
def _rust_seconds_per_evaluation(dim: int = 10, samples: int = 10000, repeats: int = 5) -> float: ...
