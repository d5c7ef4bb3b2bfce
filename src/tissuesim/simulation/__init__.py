"""``Simulation``, the object users script (``simulation.py``: its state, the system it builds,
``step``, ``run``, checkpoints), made of one mixin per concept: ``bodies.py`` (adding, naming,
finding bodies), ``loads.py`` (supports, graspers, loads, damping, a frame body's set-up),
``interactions.py`` (contact, obstacles, attachments; the contact model), ``cuts.py`` (blades,
tearing, cutting a FEM body), ``checks.py`` (checks before a step, reports after it),
``results.py`` (positions, fields, forces, energies), ``stepping.py`` (the integrator's step
function, phases, adaptive steps)."""

from __future__ import annotations

from tissuesim.records import StepRecord
from tissuesim.simulation.bodies import RESERVED_NAMES
from tissuesim.simulation.simulation import INTEGRATORS, Simulation
from tissuesim.time.grid import check_time_resolution

__all__ = ["Simulation", "StepRecord", "INTEGRATORS", "RESERVED_NAMES", "check_time_resolution"]
