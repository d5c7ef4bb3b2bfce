"""Hyperelastic material laws: psi(F), P(F) and dP/dF, batched over integration points (and a
law from its energy, ``EnergyLaw``, whose P and dP/dF SymPy derives).

The interface is in ``base.py``, law names in ``registry.py``; the laws by family in
``isotropic/`` (the (E, nu) laws, what every law shares, their Numba kernels), ``soft_tissue/``
(FEBio's laws), ``fibres/`` (fibre-reinforced laws and FEBio's fibre laws) and ``energy_law/``
(a law from its energy); visco-elasticity on any law in ``viscoelastic.py``, FEBio's solid
mixtures (sums of laws) in ``mixture.py``, fitting to test curves in ``fitting.py``, the
output's strain and stress measures in ``measures.py``, the laws' volumetric parts for mean
dilatation in ``volumetric.py`` and the PSD projection in ``psd.py``.
"""

from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.energy_law.energy import EnergyLaw, from_energy
from tissuesim.materials.fibres.fibre_exp_linear import FiberExpLinear, FiberExpLinearUncoupled
from tissuesim.materials.fibres.fibre_exp_pow import FiberExpPow, FiberExpPowUncoupled
from tissuesim.materials.fibres.fibre_pow_linear import FiberPowLinear, FiberPowLinearUncoupled
from tissuesim.materials.fibres.holzapfel_gasser_ogden import HGOUnconstrained, HolzapfelGasserOgden
from tissuesim.materials.fibres.tc_nonlinear_orthotropic import TCNonlinearOrthotropic
from tissuesim.materials.fibres.trans_iso_mooney_rivlin import (
    CoupledTransIsoMooneyRivlin,
    TransIsoMooneyRivlin,
)
from tissuesim.materials.fibres.trans_iso_veronda_westmann import TransIsoVerondaWestmann
from tissuesim.materials.fitting import FitResult, fit_material, nominal_stress
from tissuesim.materials.isotropic.corotated import FixedCorotated
from tissuesim.materials.isotropic.course_neo_hookean import CourseNeoHookean
from tissuesim.materials.isotropic.lame import lame_parameters
from tissuesim.materials.isotropic.linear import LinearElastic
from tissuesim.materials.isotropic.neo_hookean import NeoHookean
from tissuesim.materials.isotropic.stvk import StVenantKirchhoff
from tissuesim.materials.mixture import SolidMixture, UncoupledSolidMixture
from tissuesim.materials.orthotropic import (
    FungOrthotropic,
    FungOrthotropicCompressible,
    OrthotropicElastic,
)
from tissuesim.materials.psd import project_psd, project_tangent_psd
from tissuesim.materials.reactive.damage import ElasticDamage, UncoupledElasticDamage
from tissuesim.materials.reactive.reactive_viscoelastic import (
    ReactiveViscoelastic,
    UncoupledReactiveViscoelastic,
)
from tissuesim.materials.reactive.viscoelastic_damage import ViscoelasticDamage
from tissuesim.materials.registry import (
    ALIASES,
    FIBRE_LAWS,
    MATERIALS,
    SOFT_TISSUE_LAWS,
    make_material,
)
from tissuesim.materials.soft_tissue.arruda_boyce import ArrudaBoyce, CoupledArrudaBoyce
from tissuesim.materials.soft_tissue.arruda_boyce_unconstrained import ArrudaBoyceUnconstrained
from tissuesim.materials.soft_tissue.hencky import IsotropicHencky
from tissuesim.materials.soft_tissue.holmes_mow import HolmesMow, UncoupledHolmesMow
from tissuesim.materials.soft_tissue.mooney_rivlin import CoupledMooneyRivlin, MooneyRivlin
from tissuesim.materials.soft_tissue.ogden import Ogden, OgdenUnconstrained
from tissuesim.materials.soft_tissue.veronda_westmann import CoupledVerondaWestmann, VerondaWestmann
from tissuesim.materials.soft_tissue.yeoh import CoupledYeoh, Yeoh
from tissuesim.materials.viscoelastic import UncoupledViscoelastic, Viscoelastic

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
    "TransIsoVerondaWestmann",
    "CoupledTransIsoMooneyRivlin",
    "TCNonlinearOrthotropic",
    "HolmesMow",
    "UncoupledHolmesMow",
    "ArrudaBoyceUnconstrained",
    "IsotropicHencky",
    "OrthotropicElastic",
    "FungOrthotropic",
    "FungOrthotropicCompressible",
    "FiberExpPow",
    "FiberExpPowUncoupled",
    "FiberPowLinear",
    "FiberPowLinearUncoupled",
    "FiberExpLinear",
    "FiberExpLinearUncoupled",
    "SolidMixture",
    "UncoupledSolidMixture",
    "Viscoelastic",
    "UncoupledViscoelastic",
    "ElasticDamage",
    "UncoupledElasticDamage",
    "ReactiveViscoelastic",
    "UncoupledReactiveViscoelastic",
    "ViscoelasticDamage",
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
