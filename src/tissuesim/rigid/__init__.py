"""Rigid bodies: six DOFs each in the same Newton solve as the deformable bodies, and the FEM
vertices that move with them (``body.py``, ``links.py``)."""

from tissuesim.rigid.body import DOF_NAMES, RigidModel
from tissuesim.rigid.links import RigidLinks

__all__ = ["DOF_NAMES", "RigidModel", "RigidLinks"]
