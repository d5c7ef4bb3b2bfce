"""A verification result: one compared quantity (``Check``)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

__all__ = ["Check"]


@dataclass(frozen=True)
class Check:
    """One compared quantity: ``error`` is |result - reference| / |reference| (absolute when
    the reference is 0, or with ``absolute``), and the check passes when error <= tolerance."""

    problem: str
    quantity: str
    reference: float
    result: float
    tolerance: float
    absolute: bool = False

    @property
    def error(self) -> float:
        """The relative (or absolute) error of the result."""
        diff = abs(self.result - self.reference)
        if self.absolute or self.reference == 0.0:
            return diff
        return diff / abs(self.reference)

    @property
    def passed(self) -> bool:
        """True when the error is finite and within the tolerance."""
        return math.isfinite(self.error) and self.error <= self.tolerance

    def as_dict(self) -> dict:
        """The check as plain data (with error and pass), for ``--json``."""
        return {**asdict(self), "error": self.error, "pass": self.passed}
