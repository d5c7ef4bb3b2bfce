"""FEBio's rigid bodies: the ``rigid body`` material and the ``<Rigid>`` section's conditions
and loads (``conditions.py``), its rigid connectors (``connectors.py``), and both written as
the scene's ``[[rigid_bodies]]`` and ``[[rigid_joints]]`` (``scene.py``)."""

from tissuesim.febio.rigid.conditions import read_rigid, read_rigid_nodes, rigid_material
from tissuesim.febio.rigid.connectors import read_connector
from tissuesim.febio.rigid.scene import rigid_bodies, rigid_joints, rigid_material_of

__all__ = [
    "read_rigid", "read_rigid_nodes", "rigid_material", "read_connector", "rigid_bodies",
    "rigid_joints", "rigid_material_of",
]  # fmt: skip
