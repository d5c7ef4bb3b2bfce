"""Laws driven by time rather than by strain history: FEBio's prescribed active contraction
(``prescribed_contraction.py``)."""

from tissuesim.materials.active.prescribed_contraction import ACTIVE_CONTRACTION_LAWS

__all__ = ["ACTIVE_CONTRACTION_LAWS"]
