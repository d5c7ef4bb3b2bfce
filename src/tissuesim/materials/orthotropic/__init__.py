"""FEBio's orthotropic laws on the Green-Lagrange strain along three local axes:
``orthotropic elastic``, ``Fung orthotropic``, ``Fung-ortho-compressible``, ``orthotropic CLE``
and ``cubic CLE`` (``_orthotropic.py`` the engine)."""

from tissuesim.materials.orthotropic.cle import CubicCLE, OrthotropicCLE
from tissuesim.materials.orthotropic.fung_orthotropic import (
    FungOrthotropic,
    FungOrthotropicCompressible,
)
from tissuesim.materials.orthotropic.orthotropic_elastic import OrthotropicElastic

__all__ = [
    "OrthotropicElastic",
    "FungOrthotropic",
    "FungOrthotropicCompressible",
    "OrthotropicCLE",
    "CubicCLE",
]
