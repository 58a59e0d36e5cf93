from plateau import FiniteDifference as FiniteDifference
from plateau import Spsa as Spsa

__all__ = ["FiniteDifference", "Spsa"]
