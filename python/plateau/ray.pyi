"""Type stubs of ``plateau.ray``: the points of an estimate on a pool of Ray actors."""

from typing import Any, Callable, List, Mapping, Optional

import numpy as np
import numpy.typing as npt

class WorkerLostError(RuntimeError):
    """A chunk of points lost its actor more than ``max_retries`` times, or a replacement
    actor could not be started."""

class RayEvaluator:
    """A batched objective (``batched=True``, optionally ``seeded=True``) that evaluates its
    points on ``num_workers`` Ray actors, each of which calls ``make_fun()`` once. Values come
    back in the order of the points; a lost actor's points run again on a replacement."""

    def __init__(
        self,
        make_fun: Callable[[], Callable[..., Any]],
        num_workers: int = 2,
        address: Optional[str] = None,
        *,
        num_cpus_per_worker: float = 1,
        num_gpus_per_worker: float = 0,
        resources: Optional[Mapping[str, float]] = None,
        chunk_size: Optional[int] = None,
        max_retries: int = 3,
        start_timeout: Optional[float] = 600.0,
        runtime_env: Optional[Mapping[str, Any]] = None,
        ray_init_kwargs: Optional[Mapping[str, Any]] = None,
    ) -> None: ...
    def __call__(self, X: npt.ArrayLike, seeds: Optional[npt.ArrayLike] = None) -> npt.NDArray[np.float64]:
        """The values of the rows of ``X`` (with their ``seeds``), in order, as float64."""
    @property
    def num_workers(self) -> int: ...
    @property
    def actors(self) -> List[Any]:
        """The current actor handles, one per worker."""
    @property
    def chunk_size(self) -> Optional[int]:
        """Points per task, or None for ``ceil(N / (4 K))``; settable between calls."""
    @chunk_size.setter
    def chunk_size(self, value: Optional[int]) -> None: ...
    @property
    def replacements(self) -> int:
        """Actors replaced after a failure since construction."""
    @property
    def nfev(self) -> int:
        """Points whose value came back."""
    @property
    def closed(self) -> bool: ...
    def close(self) -> None:
        """Kill the actors; shut Ray down if this evaluator started it. Idempotent."""
    def shutdown(self) -> None:
        """The same as :meth:`close`."""
    def __enter__(self) -> "RayEvaluator": ...
    def __exit__(self, *exc: Any) -> None: ...

__all__ = ["RayEvaluator", "WorkerLostError"]
