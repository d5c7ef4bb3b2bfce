"""FEBio's rigid bodies: the ``rigid body`` material, the ``<Rigid>`` section (fixed,
prescribed and loaded rigid DOFs) and ``<bc type="rigid">`` node sets, as tissuesim's rigid
bodies (``tissuesim.rigid``)."""

from __future__ import annotations

from tissuesim.febio.model import FebModel
from tissuesim.febio.xml import Node

__all__ = ["rigid_material"]


def rigid_material(model: FebModel, mat: Node) -> tuple:
    """(model name, parameters, density, FEBio type, None) of a ``rigid body`` material."""
    raise mat.error("material type 'rigid body' is not supported by tissuesim yet")
