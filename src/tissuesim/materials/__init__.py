"""Hyperelastic material laws: psi(F), P(F) and dP/dF, batched over integration points (and a
law from its energy, ``EnergyLaw``, whose P and dP/dF SymPy derives)."""

from tissuesim.materials.arruda_boyce import ArrudaBoyce, CoupledArrudaBoyce
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.corotated import FixedCorotated
from tissuesim.materials.course_neo_hookean import CourseNeoHookean
from tissuesim.materials.energy import EnergyLaw, from_energy
from tissuesim.materials.fitting import FitResult, fit_material, nominal_stress
from tissuesim.materials.holzapfel_gasser_ogden import HGOUnconstrained, HolzapfelGasserOgden
from tissuesim.materials.lame import lame_parameters
from tissuesim.materials.linear import LinearElastic
from tissuesim.materials.mooney_rivlin import CoupledMooneyRivlin, MooneyRivlin
from tissuesim.materials.neo_hookean import NeoHookean
from tissuesim.materials.ogden import Ogden, OgdenUnconstrained
from tissuesim.materials.psd import project_psd, project_tangent_psd
from tissuesim.materials.registry import (
    ALIASES,
    FIBRE_LAWS,
    MATERIALS,
    SOFT_TISSUE_LAWS,
    make_material,
)
from tissuesim.materials.stvk import StVenantKirchhoff
from tissuesim.materials.trans_iso_mooney_rivlin import TransIsoMooneyRivlin
from tissuesim.materials.veronda_westmann import CoupledVerondaWestmann, VerondaWestmann
from tissuesim.materials.viscoelastic import UncoupledViscoelastic, Viscoelastic
from tissuesim.materials.yeoh import CoupledYeoh, Yeoh

__all__ = [
    "Material",
    "MaterialResponse",
    "CourseNeoHookean",
    "NeoHookean",
    "StVenantKirchhoff",
    "LinearElastic",
    "FixedCorotated",
    "MooneyRivlin",
    "CoupledMooneyRivlin",
    "Ogden",
    "OgdenUnconstrained",
    "Yeoh",
    "CoupledYeoh",
    "VerondaWestmann",
    "CoupledVerondaWestmann",
    "ArrudaBoyce",
    "CoupledArrudaBoyce",
    "HolzapfelGasserOgden",
    "HGOUnconstrained",
    "TransIsoMooneyRivlin",
    "Viscoelastic",
    "UncoupledViscoelastic",
    "EnergyLaw",
    "from_energy",
    "lame_parameters",
    "project_psd",
    "project_tangent_psd",
    "MATERIALS",
    "ALIASES",
    "SOFT_TISSUE_LAWS",
    "FIBRE_LAWS",
    "make_material",
    "fit_material",
    "FitResult",
    "nominal_stress",
]
