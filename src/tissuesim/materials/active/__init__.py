"""Laws driven by time rather than by strain history: FEBio's prescribed active contraction
(``prescribed_contraction.py``) and kinematic growth (``kinematic_growth.py``); the time they
keep, ``_time.py``."""

from tissuesim.materials.active.kinematic_growth import GROWTH_TYPES, KinematicGrowth
from tissuesim.materials.active.prescribed_contraction import ACTIVE_CONTRACTION_LAWS

__all__ = ["ACTIVE_CONTRACTION_LAWS", "GROWTH_TYPES", "KinematicGrowth"]
