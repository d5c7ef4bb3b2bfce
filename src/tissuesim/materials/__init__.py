"""Hyperelastic material laws: psi(F), P(F) and dP/dF, batched over integration points."""

from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.corotated import FixedCorotated
from tissuesim.materials.course_neo_hookean import CourseNeoHookean
from tissuesim.materials.lame import lame_parameters
from tissuesim.materials.linear import LinearElastic
from tissuesim.materials.neo_hookean import NeoHookean
from tissuesim.materials.psd import project_psd, project_tangent_psd
from tissuesim.materials.registry import MATERIALS, make_material
from tissuesim.materials.stvk import StVenantKirchhoff

__all__ = [
    "Material",
    "MaterialResponse",
    "CourseNeoHookean",
    "NeoHookean",
    "StVenantKirchhoff",
    "LinearElastic",
    "FixedCorotated",
    "lame_parameters",
    "project_psd",
    "project_tangent_psd",
    "MATERIALS",
    "make_material",
]
