"""FEBio's ``<Material>`` section and ``<MeshData>`` directions: the reader (``reading.py``),
the tables of FEBio's material types (``laws.py``), the laws' directions (``axes.py``) and
FEBio's hyperelastic laws given as expressions (``expressions.py``)."""

from tissuesim.febio.materials.reading import (
    FIBRE_TYPES,
    MATERIAL_TYPES,
    MIXTURES,
    UNCOUPLED,
    MixtureOrientation,
    Orientation,
    axes_from,
    body_directions,
    read_materials,
    read_mesh_data,
    with_directions,
)

__all__ = [
    "MATERIAL_TYPES", "UNCOUPLED", "FIBRE_TYPES", "MIXTURES", "Orientation",
    "MixtureOrientation", "read_materials", "read_mesh_data", "axes_from", "body_directions",
    "with_directions",
]  # fmt: skip
