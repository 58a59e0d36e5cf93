"""The Rust extension module; its public names are re-exported by ``plateau``."""

from typing import Any

from plateau import PAPER_SIGMA_MIN as PAPER_SIGMA_MIN
from plateau import PAPER_WARMUP as PAPER_WARMUP
from plateau import Adam as Adam
from plateau import Annealer as Annealer
from plateau import FiniteDifference as FiniteDifference
from plateau import PlateauFreeGradient as PlateauFreeGradient
from plateau import Spsa as Spsa

def __getattr__(name: str) -> Any: ...
