"""Identification of tissue parameters from measurements: the derivatives of what a run
reports with respect to its parameters (``sensitivity.py``), and fits of parameters to
measured forces and displacements by least squares with those derivatives (``fit.py``)."""

from __future__ import annotations

from tissuesim.identification.fit import Identification, identify
from tissuesim.identification.observations import (
    ContactForce,
    Displacement,
    Reaction,
    RigidForce,
    SurfaceDistance,
)
from tissuesim.identification.sensitivity import Sensitivities, sensitivities

__all__ = [
    "ContactForce",
    "Displacement",
    "Identification",
    "Reaction",
    "RigidForce",
    "Sensitivities",
    "identify",
    "sensitivities",
    "SurfaceDistance",
]
