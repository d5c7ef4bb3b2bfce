"""tissuesim: soft-tissue simulation with finite elements and meshless frames.

The names users need most are re-exported here; each lives in one module (see docs/design.md).
"""

from __future__ import annotations

from tissuesim._version import __version__
from tissuesim.contact.obstacles import capsule, cylinder, plane, sphere
from tissuesim.contact.pairs import ContactPair
from tissuesim.errors import (
    ConvergenceError,
    InputError,
    InstabilityError,
    InvertedElementError,
    MaterialError,
    MeshError,
    OutputError,
    ResourceError,
    RunError,
    SceneError,
    TissueSimError,
)
from tissuesim.frames.sampling import read_surface
from tissuesim.materials import (
    ArrudaBoyce,
    CoupledArrudaBoyce,
    CoupledMooneyRivlin,
    CoupledVerondaWestmann,
    CoupledYeoh,
    CourseNeoHookean,
    EnergyLaw,
    FixedCorotated,
    HGOUnconstrained,
    HolzapfelGasserOgden,
    LinearElastic,
    MooneyRivlin,
    NeoHookean,
    Ogden,
    OgdenUnconstrained,
    StVenantKirchhoff,
    TransIsoMooneyRivlin,
    UncoupledViscoelastic,
    VerondaWestmann,
    Viscoelastic,
    Yeoh,
    fit_material,
    from_energy,
    make_material,
)
from tissuesim.mesh import Mesh, box, ellipsoid, mesh_surface, read_mesh, rectangle
from tissuesim.mesh.queries import select
from tissuesim.simulation import Simulation
from tissuesim.solve.newton import NewtonOptions

__all__ = [
    "__version__",
    "ConvergenceError",
    "InputError",
    "InstabilityError",
    "OutputError",
    "ResourceError",
    "RunError",
    "ArrudaBoyce",
    "ContactPair",
    "CoupledArrudaBoyce",
    "CoupledMooneyRivlin",
    "CoupledVerondaWestmann",
    "CoupledYeoh",
    "CourseNeoHookean",
    "EnergyLaw",
    "FixedCorotated",
    "HGOUnconstrained",
    "HolzapfelGasserOgden",
    "InvertedElementError",
    "LinearElastic",
    "MaterialError",
    "Mesh",
    "MeshError",
    "MooneyRivlin",
    "NeoHookean",
    "NewtonOptions",
    "Ogden",
    "OgdenUnconstrained",
    "SceneError",
    "Simulation",
    "StVenantKirchhoff",
    "TissueSimError",
    "TransIsoMooneyRivlin",
    "UncoupledViscoelastic",
    "VerondaWestmann",
    "Viscoelastic",
    "Yeoh",
    "box",
    "capsule",
    "cylinder",
    "ellipsoid",
    "fit_material",
    "from_energy",
    "make_material",
    "mesh_surface",
    "plane",
    "read_mesh",
    "read_surface",
    "rectangle",
    "select",
    "sphere",
]
