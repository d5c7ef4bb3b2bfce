"""FEBio's material types that tissuesim runs: the type -> (tissuesim law, parameter names)
table, the fibre laws and what their directions are, the mixtures, the viscoelastic wrappers and
the uncoupled laws (which FEBio runs with its three-field element). ``materials.py`` reads the
``<material>`` elements with these tables."""

from __future__ import annotations

__all__ = [
    "VECTOR_PARAMETERS",
    "MATERIAL_TYPES",
    "FIBRES_ONLY",
    "MIXTURES",
    "FIBRE_TYPES",
    "UNCOUPLED",
    "VISCOELASTIC",
    "DAMAGE",
    "REACTIVE_VISCOELASTIC",
    "CONTINUOUS",
    "ACTIVE",
    "CURVE_PARAMETERS",
    "NO_ENERGY",
]

#: FEBio material types tissuesim runs -> (model, FEBio parameter -> tissuesim keyword; None:
#: the law takes FEBio's parameter names as they are)
MATERIAL_TYPES = {
    "neo-Hookean": ("neo_hookean", {"E": "youngs_modulus", "v": "poisson_ratio"}),
    "isotropic elastic": ("stvk", {"E": "youngs_modulus", "v": "poisson_ratio"}),
    # FEBio's FEStVenantKirchhoff: the same stress as isotropic elastic's
    "St.Venant-Kirchhoff": ("stvk", {"E": "youngs_modulus", "v": "poisson_ratio"}),
    **{
        name: (name, None)
        for name in (
            "Mooney-Rivlin",
            "coupled Mooney-Rivlin",
            "Ogden",
            "Ogden unconstrained",
            "Yeoh",
            "Veronda-Westmann",
            "coupled Veronda-Westmann",
            "Arruda-Boyce",
            "Holzapfel-Gasser-Ogden",
            "HGO unconstrained",
            "trans iso Mooney-Rivlin",
            "trans iso Veronda-Westmann",
            "coupled trans-iso Mooney-Rivlin",
            "orthotropic elastic",
            "Fung orthotropic",
            "Fung-ortho-compressible",
            "Holmes-Mow",
            "TC nonlinear orthotropic",
            "Arruda-Boyce unconstrained",
            "isotropic Hencky",
            "orthotropic CLE",
            "cubic CLE",
            "porous neo-Hookean",
            "Shenoy",
            "muscle material",
            "uncoupled Holmes-Mow",
            "fiber-exp-pow",
            "fiber-exp-pow-uncoupled",
            "fiber-pow-linear",
            "fiber-pow-linear-uncoupled",
            "continuous fiber distribution",
            "continuous fiber distribution uncoupled",
            "2D trans iso Mooney-Rivlin",
            "Mooney-Rivlin von Mises Fibers",
        )
    },
    **{
        name: (name, {"c3": "c3", "c4": "c4", "c5": "c5", "lambda": "lam_max"})
        for name in ("fiber-exp-linear", "uncoupled fiber-exp-linear")
    },
    **{
        f"{pre}prescribed {kind} active contraction": (
            f"{pre}prescribed {kind} active contraction",
            {"T0": "T0"},
        )
        for pre in ("", "uncoupled ")
        for kind in ("isotropic", "trans iso", "uniaxial")
    },
}
#: FEBio's prescribed active contraction (``materials/active/``): an active stress T0(t), read
#: as a solid mixture's component only (it adds no stiffness); n0 its first local axis
ACTIVE = {
    f"{pre}prescribed {kind} active contraction"
    for pre in ("", "uncoupled ")
    for kind in ("isotropic", "trans iso", "uniaxial")
}
#: FEBio's laws whose stress is not the derivative of an energy of F (their tangent is not
#: symmetric), which tissuesim, minimising an energy in each step, does not run: the reason
NO_ENERGY = {
    **{
        name: "its Cauchy stress 2 mu D + (kappa - 2 mu/3) tr(D) I, D = sym((F - Fp) F^-1)/dt "
        "(FEBio's rate in a quasi-static step), is not the derivative of an energy of F"
        for name in ("Newtonian viscous solid", "Newtonian viscous solid uncoupled")
    },
    "active_contraction": "FEBio's active fibre stress Tmax f(lambda~) a (x) a (lambda~ = "
    "J^(-1/3) |F a0|) is not the derivative of an energy of F",
}
#: parameters that may follow a load curve (``<T0 lc="1">``: value times the curve)
CURVE_PARAMETERS = {name: ("T0",) for name in ACTIVE}
#: FEBio's fibre laws, read as components of a solid mixture only (they have no matrix)
FIBRES_ONLY = {
    "fiber-exp-pow", "fiber-exp-pow-uncoupled", "fiber-pow-linear", "fiber-pow-linear-uncoupled",
    "fiber-exp-linear", "uncoupled fiber-exp-linear",
    "continuous fiber distribution", "continuous fiber distribution uncoupled",
}  # fmt: skip
#: FEBio's continuous fibre distributions: their <fibers>, <distribution> and <scheme> are
#: tables of a type and its parameters (``materials/fibres/continuous_distribution.py``)
CONTINUOUS = {"continuous fiber distribution", "continuous fiber distribution uncoupled"}
#: FEBio's solid mixtures -> tissuesim's model
MIXTURES = {"solid mixture": "solid_mixture", "uncoupled solid mixture": "uncoupled_solid_mixture"}
#: the fibre laws: FEBio type -> what their directions are ("axes": e1, e2; "fiber": Q fiber)
FIBRE_TYPES = {
    "Holzapfel-Gasser-Ogden": "axes",
    "HGO unconstrained": "axes",
    "trans iso Mooney-Rivlin": "fiber",
    "trans iso Veronda-Westmann": "fiber",
    "coupled trans-iso Mooney-Rivlin": "fiber",
    **{
        name: "axes"
        for name in (
            "orthotropic elastic",
            "Fung orthotropic",
            "Fung-ortho-compressible",
            "TC nonlinear orthotropic",
            "orthotropic CLE",
            "cubic CLE",
        )
    },
    **{name: "fiber" for name in FIBRES_ONLY},
    **{name: "axes" for name in CONTINUOUS},
    "2D trans iso Mooney-Rivlin": "fiber",
    "Mooney-Rivlin von Mises Fibers": "axes",
    **{name: "fiber" for name in ACTIVE if "isotropic" not in name},
    "muscle material": "fiber",
}
#: the uncoupled laws, which FEBio runs with its three-field (mean dilatation) hex8 / tet10
UNCOUPLED = {
    "Mooney-Rivlin", "Ogden", "Yeoh", "Veronda-Westmann", "Arruda-Boyce",
    "Holzapfel-Gasser-Ogden", "trans iso Mooney-Rivlin", "trans iso Veronda-Westmann",
    "Fung orthotropic", "uncoupled Holmes-Mow", "TC nonlinear orthotropic",
    "uncoupled viscoelastic",
    "uncoupled solid mixture", "fiber-exp-pow-uncoupled", "fiber-pow-linear-uncoupled",
    "uncoupled fiber-exp-linear", "continuous fiber distribution uncoupled",
    "2D trans iso Mooney-Rivlin", "Mooney-Rivlin von Mises Fibers",
    *(name for name in ACTIVE if name.startswith("uncoupled")),
    "muscle material",
}  # fmt: skip
VISCOELASTIC = {
    "viscoelastic": "viscoelastic",
    "uncoupled viscoelastic": "uncoupled_viscoelastic",
    "viscoelastic damage": "viscoelastic_damage",  # its <elastic> an elastic damage
}
#: FEBio's damage wrappers (alone or a solid mixture's component) -> tissuesim's model
DAMAGE = {
    "elastic damage": "elastic_damage",
    "uncoupled elastic damage": "uncoupled_elastic_damage",
}
#: parameters given as a list (one value per axis), by FEBio type
VECTOR_PARAMETERS = {
    "TC nonlinear orthotropic": ("beta", "ksi"),
    "2D trans iso Mooney-Rivlin": ("w", "a"),
}
#: FEBio's reactive viscoelastic wrappers -> tissuesim's model
REACTIVE_VISCOELASTIC = {
    "reactive viscoelastic": "reactive_viscoelastic",
    "uncoupled reactive viscoelastic": "uncoupled_reactive_viscoelastic",
    # (1 - D) on a reactive viscoelastic <viscoelastic>, D of its strong bonds' law: the same
    # law as a reactive viscoelastic whose <elastic> is an elastic damage
    "reactive viscoelastic damage": "reactive_viscoelastic",
}
