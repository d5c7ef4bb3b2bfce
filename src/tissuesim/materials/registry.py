"""Material laws by name, as used in scene files: ``make_material("neo_hookean", ...)``.

The soft-tissue laws carry FEBio's names (its ``type`` with spaces and dashes as underscores):
``mooney_rivlin``, ``ogden``, ``yeoh``, ``veronda_westmann`` and ``arruda_boyce`` are FEBio's
uncoupled laws; ``coupled_mooney_rivlin``, ``coupled_veronda_westmann`` and
``ogden_unconstrained`` its coupled ones; ``coupled_yeoh`` and ``coupled_arruda_boyce`` are
tissuesim's coupled forms where FEBio has none. ``<law>_uncoupled`` and ``<law>_coupled`` are
accepted as aliases (``ALIASES``). ``viscoelastic`` and ``uncoupled_viscoelastic`` wrap another
law given as ``elastic`` (a material or a table with its ``model``), ``VISCOELASTIC_LAWS``.
``elastic_damage`` and ``uncoupled_elastic_damage`` scale another law (``elastic``) by 1 - D
(``DAMAGE_LAWS``; a mixture with such a component steps its history, ``HISTORY_MIXTURES``);
``reactive_viscoelastic`` and ``uncoupled_reactive_viscoelastic`` take ``elastic`` and ``bond``
laws (``REACTIVE_VISCOELASTIC_LAWS``); ``viscoelastic_damage`` takes an ``elastic_damage``.
``kinematic_growth`` takes an ``elastic`` law at Fe = F Fg^-1 (``materials/active/``),
``prestrain_elastic`` one at F Fp (``prestrain.py``).
``energy`` is a law from its strain-energy density ``psi`` (``EnergyLaw``), its other keys the
parameters psi names. ``solid_mixture`` and ``uncoupled_solid_mixture`` sum the laws given as
``components`` (``MIXTURES``); FEBio's fibre laws ``fiber_exp_pow``, ``fiber_pow_linear``,
``fiber_exp_linear`` (and their ``_uncoupled`` forms) are meant as their components.
"""

from __future__ import annotations

import difflib
import inspect

from tissuesim.errors import MaterialError
from tissuesim.materials.active import ACTIVE_CONTRACTION_LAWS, KinematicGrowth
from tissuesim.materials.base import Material
from tissuesim.materials.energy_law.energy import EnergyLaw
from tissuesim.materials.fibres.continuous_distribution import (
    ContinuousFiberDistribution,
    ContinuousFiberDistributionUncoupled,
)
from tissuesim.materials.fibres.fibre_exp_linear import FiberExpLinear, FiberExpLinearUncoupled
from tissuesim.materials.fibres.fibre_exp_pow import FiberExpPow, FiberExpPowUncoupled
from tissuesim.materials.fibres.fibre_pow_linear import FiberPowLinear, FiberPowLinearUncoupled
from tissuesim.materials.fibres.holzapfel_gasser_ogden import HGOUnconstrained, HolzapfelGasserOgden
from tissuesim.materials.fibres.mooney_rivlin_von_mises import MooneyRivlinVonMisesFibers
from tissuesim.materials.fibres.tc_nonlinear_orthotropic import TCNonlinearOrthotropic
from tissuesim.materials.fibres.trans_iso_2d_mooney_rivlin import TransIso2DMooneyRivlin
from tissuesim.materials.fibres.trans_iso_mooney_rivlin import (
    CoupledTransIsoMooneyRivlin,
    TransIsoMooneyRivlin,
)
from tissuesim.materials.fibres.trans_iso_veronda_westmann import TransIsoVerondaWestmann
from tissuesim.materials.isotropic.corotated import FixedCorotated
from tissuesim.materials.isotropic.course_neo_hookean import CourseNeoHookean
from tissuesim.materials.isotropic.linear import LinearElastic
from tissuesim.materials.isotropic.neo_hookean import NeoHookean
from tissuesim.materials.isotropic.stvk import StVenantKirchhoff
from tissuesim.materials.mixture import MIXTURES
from tissuesim.materials.multigeneration import Multigeneration
from tissuesim.materials.muscle import MuscleMaterial
from tissuesim.materials.orthotropic import (
    CubicCLE,
    FungOrthotropic,
    FungOrthotropicCompressible,
    OrthotropicCLE,
    OrthotropicElastic,
)
from tissuesim.materials.porous_neo_hookean import PorousNeoHookean
from tissuesim.materials.prestrain import PrestrainElastic
from tissuesim.materials.reactive.damage import DAMAGE_LAWS
from tissuesim.materials.reactive.history_mixture import HISTORY_MIXTURES
from tissuesim.materials.reactive.reactive_viscoelastic import REACTIVE_VISCOELASTIC_LAWS
from tissuesim.materials.reactive.viscoelastic_damage import ViscoelasticDamage
from tissuesim.materials.shenoy import Shenoy
from tissuesim.materials.soft_tissue.arruda_boyce import ArrudaBoyce, CoupledArrudaBoyce
from tissuesim.materials.soft_tissue.arruda_boyce_unconstrained import ArrudaBoyceUnconstrained
from tissuesim.materials.soft_tissue.hencky import IsotropicHencky
from tissuesim.materials.soft_tissue.holmes_mow import HolmesMow, UncoupledHolmesMow
from tissuesim.materials.soft_tissue.mooney_rivlin import CoupledMooneyRivlin, MooneyRivlin
from tissuesim.materials.soft_tissue.ogden import Ogden, OgdenUnconstrained
from tissuesim.materials.soft_tissue.veronda_westmann import CoupledVerondaWestmann, VerondaWestmann
from tissuesim.materials.soft_tissue.yeoh import CoupledYeoh, Yeoh
from tissuesim.materials.viscoelastic import VISCOELASTIC_LAWS
from tissuesim.validate import short

__all__ = [
    "MATERIALS",
    "ALIASES",
    "SOFT_TISSUE_LAWS",
    "FIBRE_LAWS",
    "FEBIO_LAWS",
    "MIXTURES",
    "make_material",
    "law_class",
]

#: the laws with their own parameters (FEBio's names), not (E, nu) or (mu, lambda)
SOFT_TISSUE_LAWS: tuple[type[Material], ...] = (
    MooneyRivlin,
    CoupledMooneyRivlin,
    Ogden,
    OgdenUnconstrained,
    Yeoh,
    CoupledYeoh,
    VerondaWestmann,
    CoupledVerondaWestmann,
    ArrudaBoyce,
    CoupledArrudaBoyce,
    HolmesMow,
    UncoupledHolmesMow,
    ArrudaBoyceUnconstrained,
    IsotropicHencky,
)

#: the fibre-reinforced laws (directions per body, element or point): FEBio's names too
FIBRE_LAWS: tuple[type[Material], ...] = (
    HolzapfelGasserOgden,
    HGOUnconstrained,
    TransIsoMooneyRivlin,
    TransIsoVerondaWestmann,
    CoupledTransIsoMooneyRivlin,
    TCNonlinearOrthotropic,
    OrthotropicElastic,
    FungOrthotropic,
    FungOrthotropicCompressible,
    FiberExpPow,
    FiberExpPowUncoupled,
    FiberPowLinear,
    FiberPowLinearUncoupled,
    FiberExpLinear,
    FiberExpLinearUncoupled,
    ContinuousFiberDistribution,
    ContinuousFiberDistributionUncoupled,
    TransIso2DMooneyRivlin,
    MooneyRivlinVonMisesFibers,
)

#: fibre laws with FEBio's own parameters (no E, nu): in FEBIO_LAWS, not MATERIALS
FEBIO_FIBRE_LAWS: tuple[type[Material], ...] = (
    ContinuousFiberDistribution,
    ContinuousFiberDistributionUncoupled,
    TransIso2DMooneyRivlin,
    MooneyRivlinVonMisesFibers,
)

MATERIALS: dict[str, type[Material]] = {
    cls.name: cls
    for cls in (
        CourseNeoHookean,
        NeoHookean,
        StVenantKirchhoff,
        LinearElastic,
        FixedCorotated,
        *SOFT_TISSUE_LAWS,
        *(law for law in FIBRE_LAWS if law not in FEBIO_FIBRE_LAWS),
    )
}

#: FEBio's laws with FEBio's own parameters that are not elastic laws on their own, or not of
#: the families above: the prescribed active contractions (a stress in time, a mixture's
#: component), the conewise linear elastic laws, the porous neo-Hookean, Shenoy and muscle
FEBIO_LAWS: dict[str, type[Material]] = {
    **ACTIVE_CONTRACTION_LAWS,
    OrthotropicCLE.name: OrthotropicCLE,
    CubicCLE.name: CubicCLE,
    PorousNeoHookean.name: PorousNeoHookean,
    Shenoy.name: Shenoy,
    MuscleMaterial.name: MuscleMaterial,
    **{law.name: law for law in FEBIO_FIBRE_LAWS},
}

#: other spellings of the soft-tissue laws' names: "<law>_uncoupled", "<law>_coupled"
ALIASES: dict[str, str] = {
    **{f"{law}_uncoupled": law for law in ("mooney_rivlin", "yeoh", "veronda_westmann")},
    **{f"{law}_coupled": f"coupled_{law}" for law in ("mooney_rivlin", "yeoh", "veronda_westmann")},
    "arruda_boyce_uncoupled": "arruda_boyce",
    "arruda_boyce_coupled": "coupled_arruda_boyce",
    "ogden_uncoupled": "ogden",
    "ogden_coupled": "ogden_unconstrained",
    "fibre_exp_pow": "fiber_exp_pow",
    "fibre_exp_pow_uncoupled": "fiber_exp_pow_uncoupled",
    "fibre_pow_linear": "fiber_pow_linear",
    "fibre_pow_linear_uncoupled": "fiber_pow_linear_uncoupled",
    "fibre_exp_linear": "fiber_exp_linear",
    "fibre_exp_linear_uncoupled": "fiber_exp_linear_uncoupled",
    "uncoupled_fiber_exp_linear": "fiber_exp_linear_uncoupled",
}


def _key(model: object) -> str:
    key = str(model).strip().lower().replace("-", "_").replace(" ", "_")
    return ALIASES.get(key, key)


def law_class(model: object) -> type[Material] | None:
    """The class ``make_material(model, ...)`` builds, or None (a wrapper, an energy law or an
    unknown name)."""
    key = _key(model)
    return MATERIALS.get(key) or FEBIO_LAWS.get(key) or MIXTURES.get(key)


def _suggest(word: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=3, cutoff=0.5)
    hint = f"did you mean {' or '.join(repr(c) for c in close)}? " if close else ""
    return f"{hint}valid: {', '.join(sorted(choices))}"


def _viscoelastic(key: str, params: dict) -> Material:
    """A Prony-series wrapper: ``elastic`` a material or a table with its ``model``
    (``viscoelastic_damage``: an ``elastic_damage``)."""
    allowed = ["elastic", "g", "tau", "g0"]
    for name in params:
        if name not in allowed:
            raise MaterialError(
                f"unknown parameter {short(name)} for material {key!r}; {_suggest(name, allowed)}"
            )
    elastic = params.get("elastic")
    if isinstance(elastic, dict):
        table = dict(elastic)
        if "model" not in table:
            raise MaterialError(f"{key}: elastic needs its model (e.g. 'neo_hookean')")
        try:
            elastic = make_material(table.pop("model"), **table)
        except MaterialError as exc:
            raise MaterialError(f"{key}: elastic: {exc}") from None
    rest = {k: v for k, v in params.items() if k != "elastic"}
    if key == ViscoelasticDamage.name:
        return ViscoelasticDamage(elastic, **rest)
    return VISCOELASTIC_LAWS[key](elastic, **rest)


def _elastic_table(key: str, elastic: object, extra: dict) -> object:
    """A wrapper's ``elastic``: a material, or a table with its model (plus ``extra``: the
    directions a FEBio mixture gives its component, meant for the wrapped law)."""
    if not isinstance(elastic, dict):
        if extra:
            name = next(iter(extra))
            raise MaterialError(f"unknown parameter {short(name)} for material {key!r}")
        return elastic
    table = {**elastic, **extra}
    if "model" not in table:
        raise MaterialError(f"{key}: elastic needs its model (e.g. 'neo_hookean')")
    try:
        return make_material(table.pop("model"), **table)
    except MaterialError as exc:
        raise MaterialError(f"{key}: elastic: {exc}") from None


def _damage(key: str, params: dict) -> Material:
    """A damage wrapper: ``elastic`` (a material or a table), ``damage`` (the CDF table),
    ``criterion``, ``density`` (uncoupled: ``k``, ``pressure_model``); other keys (a mixture
    component's directions) go to elastic."""
    own = ("elastic", "damage", "criterion", "density")
    if DAMAGE_LAWS[key].uncoupled:
        own += ("k", "pressure_model")
    extra = {k: v for k, v in params.items() if k not in own}
    elastic = params.get("elastic")
    if DAMAGE_LAWS[key].uncoupled and isinstance(elastic, dict) and "k" not in elastic:
        cls = law_class(elastic.get("model"))  # its deviatoric part is used: any k will do
        if cls is not None and "k" in inspect.signature(cls.__init__).parameters:
            elastic = {**elastic, "k": 1.0}
    elastic = _elastic_table(key, elastic, extra)
    rest = {k: v for k, v in params.items() if k in own and k != "elastic"}
    return DAMAGE_LAWS[key](elastic, **rest)


def _reactive_viscoelastic(key: str, params: dict) -> Material:
    """Reactive visco-elasticity: ``elastic`` and ``bond`` materials or tables (uncoupled: a
    law's own k is not used, any will do), ``relaxation``, ``recruitment`` and the wrapper's
    parameters."""
    cls = REACTIVE_VISCOELASTIC_LAWS[key]
    allowed = ["elastic", "bond", "relaxation", "recruitment", "kinetics", "trigger", "emin",
               "wmin"]  # fmt: skip
    allowed += ["k", "pressure_model"] if cls.uncoupled else []
    for name in params:
        if name not in allowed:
            raise MaterialError(
                f"unknown parameter {short(name)} for material {key!r}; {_suggest(name, allowed)}"
            )
    laws = {}
    for part in ("elastic", "bond"):
        value = params.get(part)
        if cls.uncoupled and isinstance(value, dict) and "k" not in value:
            law = law_class(value.get("model"))
            if law is not None and "k" in inspect.signature(law.__init__).parameters:
                value = {**value, "k": 1.0}
        try:
            laws[part] = _elastic_table(key, value, {})
        except MaterialError as exc:
            raise MaterialError(str(exc).replace(": elastic:", f": {part}:")) from None
    rest = {k: v for k, v in params.items() if k not in ("elastic", "bond")}
    return cls(laws["elastic"], bond=laws["bond"], **rest)


def _mixture(key: str, params: dict) -> Material:
    """A solid mixture: ``components`` materials or tables with their model; a component law of
    an uncoupled mixture that takes k gets the mixture's (FEBio ignores the component's)."""
    components = params.get("components")
    if isinstance(components, (list, tuple)):
        k = params.get("k") if key == "uncoupled_solid_mixture" else None
        built = []
        for i, value in enumerate(components):
            if not isinstance(value, dict):
                built.append(value)  # a material; anything else the mixture refuses
                continue
            table = dict(value)
            if "model" not in table:
                raise MaterialError(f"{key}: components[{i}] needs its model (e.g. 'neo_hookean')")
            model = table.pop("model")
            cls = law_class(model)
            if k is not None and cls is not None:
                if "k" in inspect.signature(cls.__init__).parameters:
                    table["k"] = k
            try:
                built.append(make_material(model, **table))
            except MaterialError as exc:
                raise MaterialError(f"{key}: components[{i}]: {exc}") from None
        params = {**params, "components": built}
        if any(hasattr(c, "accept_step") for c in built):  # a damage component's history
            return HISTORY_MIXTURES[key](**params)
    return MIXTURES[key](**params)


def make_material(model: str, **params: object) -> Material:
    """Build the law registered as ``model`` with keyword parameters (e.g. E and nu, or a
    soft-tissue law's own: ``make_material("ogden", c=[1e3], m=[8.0], k=1e5)``; a law from its
    energy: ``make_material("energy", psi="c1*(I1b - 3) + k/2*log(J)**2", c1=1e3, k=1e5)``).

    FEBio's law names work as written there (``"Mooney-Rivlin"``, ``"Ogden unconstrained"``):
    case, spaces and dashes do not matter."""
    key = _key(model)
    if key in MIXTURES:
        return _mixture(key, params)
    if key in VISCOELASTIC_LAWS or key == ViscoelasticDamage.name:
        return _viscoelastic(key, params)
    if key in DAMAGE_LAWS:
        return _damage(key, params)
    if key in REACTIVE_VISCOELASTIC_LAWS:
        return _reactive_viscoelastic(key, params)
    if key == Multigeneration.name:  # each generation's solid: a material or a table
        gens = params.get("generations")
        if isinstance(gens, (list, tuple)):
            gens = [
                {**g, "solid": _elastic_table(f"{key}: generations[{i}]", g.get("solid"), {})}
                if isinstance(g, dict)
                else g
                for i, g in enumerate(gens)
            ]
        return Multigeneration(**{**params, "generations": gens})
    if key == PrestrainElastic.name:  # its elastic law: a material or a table
        elastic = _elastic_table(key, params.get("elastic"), {})
        return PrestrainElastic(**{**params, "elastic": elastic})
    if key == KinematicGrowth.name:  # its elastic law: a material or a table
        elastic = _elastic_table(key, params.get("elastic"), {})
        return KinematicGrowth(**{**params, "elastic": elastic})
    if key == EnergyLaw.name:
        if "psi" not in params:
            raise MaterialError(
                "energy needs psi, the strain-energy density, e.g. psi = "
                "'mu/2*(I1 - 3) - mu*log(J) + lam/2*log(J)**2' with mu and lam"
            )
        return EnergyLaw(params.pop("psi"), **params)
    if key not in MATERIALS and key not in FEBIO_LAWS:
        names = [
            *FEBIO_LAWS,
            *MATERIALS,
            *VISCOELASTIC_LAWS,
            *DAMAGE_LAWS,
            *REACTIVE_VISCOELASTIC_LAWS,
        ]
        names += [KinematicGrowth.name, PrestrainElastic.name, Multigeneration.name]
        names.append(ViscoelasticDamage.name)
        names += [*MIXTURES, EnergyLaw.name]
        raise MaterialError(f"unknown material model {short(model)}; {_suggest(key, names)}")
    cls = MATERIALS.get(key) or FEBIO_LAWS[key]
    sig = inspect.signature(cls.__init__).parameters
    allowed = [n for n, p in sig.items() if p.kind is inspect.Parameter.KEYWORD_ONLY]
    for name in params:
        if name not in allowed:
            raise MaterialError(
                f"unknown parameter {short(name)} for material {key!r}; {_suggest(name, allowed)}"
            )
    return cls(**params)
