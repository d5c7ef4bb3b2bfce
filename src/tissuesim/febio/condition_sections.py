"""FEBio's ``<Boundary>``, ``<Loads>``, ``<LoadData>``, ``<Contact>``, ``<Globals>`` and
``<Output>`` sections, in FEBio 3.0's and 4.0's spellings."""

from __future__ import annotations

import re

import numpy as np

from tissuesim.febio.model import (
    Curve,
    FebModel,
    Load,
    _children,
    _flag,
    _floats,
    _int_attr,
    _load,
    _unsupported,
)
from tissuesim.febio.xml import Node

__all__ = ["SECTIONS", "CONTACT_TYPES", "INTERPOLATIONS"]

AXES = {"x": 0, "y": 1, "z": 2}
#: FEBio's sliding contacts (tissuesim's penalty contact, contact/penalty/) and rigid wall
CONTACT_TYPES = ("sliding-elastic", "sliding-facet-on-facet", "sliding-node-on-facet", "rigid_wall")
#: FEBio's tied contacts: penalty contact with the points held where they project at rest
TIED_TYPES = ("tied-elastic", "tied-node-on-facet", "tied-facet-on-facet", "sticky")
#: contacts whose closest-point projection handles FEBio's special cases (edges, nodes:
#: contact/penalty/special_cases.py); sliding-elastic and tied-elastic cast rays instead.
#: FEBio's sliding-facet-on-facet and sliding-node-on-facet do too, but not here: with them
#: co13 went from 7.6e-9 to 3.6e-4 of FEBio's norm and dy04 from 4.8e-4 to -2.1e-2, while the
#: node-on-facet models that stop (co15, co20, co21, co36) stop later but still stop
SPECIAL_CASE_TYPES = ("tied-node-on-facet", "tied-facet-on-facet", "sticky")
#: children of <contact> that tune FEBio's enforcement (penalty, augmentation, search), read
#: by _penalty_settings; FEBio's search_radius, seg_up, knmult, ktmult and
#: symmetric_stiffness are not used (tissuesim's search and exact Hessian)
CONTACT_TUNING = {
    "laugon", "tolerance", "gaptol", "penalty", "auto_penalty", "update_penalty", "two_pass",
    "knmult", "search_tol", "symmetric_stiffness", "search_radius", "seg_up", "minaug",
    "maxaug", "node_reloc", "smooth_aug", "flip_primary", "flip_secondary", "ktmult",
    "fric_penalty",
}  # fmt: skip
#: load curve interpolations tissuesim writes as expressions of t
INTERPOLATIONS = ("LINEAR", "STEP", "SMOOTH", "SMOOTH STEP")


def _node_set(model: FebModel, node: Node, attr: str = "node_set") -> str:
    """The node set a condition names (FEBio 4's "@surface:name" too), checked."""
    name = node.attrib.get(attr)
    if name is None:
        raise node.error(f"missing the {attr} attribute")
    if name.startswith("@surface:"):
        surface = name.removeprefix("@surface:")
        if surface not in model.surfaces:
            raise node.error(f"no Surface named {surface!r}")
        model.node_sets.setdefault(name, model.surface_nodes[surface])
    elif name.startswith("@elem_set:"):  # FEBio 4: the nodes of an element set or a part
        elements = name.removeprefix("@elem_set:")
        if elements in model.parts:
            nodes = np.unique(model.parts[elements][1])
        elif elements in model.element_sets:
            members = model.element_sets[elements][0]
            nodes = np.unique(np.concatenate([model.parts[p][1][r] for p, r in members]))
        else:
            raise node.error(f"no ElementSet or part named {elements!r}")
        model.node_sets.setdefault(name, nodes)
    elif name not in model.node_sets:
        raise node.error(f"no NodeSet named {name!r}")
    if len(model.node_sets[name]) == 0:  # FEBio would run it on nothing: a silent no-op
        raise node.error(
            f"node set {name!r} is empty, so this <{node.tag}> would act on no node: give the "
            "set its nodes, or remove the condition"
        )
    return name


def _boundary(model: FebModel, section: Node) -> None:
    for bc in section.children:
        if bc.tag != "bc":
            raise _unsupported(bc, "expected <bc>")
        kind = bc.attrib.get("type", "")
        name = bc.attrib.get("name")
        if kind in ("zero displacement", "fix"):
            nodes = _node_set(model, bc)
            p = _children(bc, {"x_dof", "y_dof", "z_dof", "dofs"})
            if "dofs" in p:
                axes = [a.strip() for a in p["dofs"].text.split(",") if a.strip()]
                bad = [a for a in axes if a not in AXES]
                if bad:
                    raise p["dofs"].error(f"dof {bad[0]!r}: tissuesim fixes x, y and z")
                comps = sorted(AXES[a] for a in axes)
            else:
                comps = [AXES[t[0]] for t in ("x_dof", "y_dof", "z_dof") if t in p and _flag(p[t])]
            if not comps:
                raise bc.error("fixes no degree of freedom")
            model.dirichlet.append(
                (nodes, None if comps == [0, 1, 2] else comps, None, name, model.window)
            )
        elif kind == "prescribed displacement":
            nodes = _node_set(model, bc)
            p = _children(bc, {"dof", "value", "scale", "relative"})
            if "dof" not in p or p["dof"].text not in AXES:
                raise bc.error("needs <dof> x, y or z")
            value = p.get("value", p.get("scale"))
            if value is None:
                raise bc.error("needs a <value> (FEBio 4) or <scale> (FEBio 3)")
            later = model.window is not None and model.window[0] > 0.0
            if "relative" in p and _flag(p["relative"]) and later:  # from where the step starts
                raise p["relative"].error(
                    "relative = 1 in a step after the first: tissuesim prescribes displacements "
                    "from the reference configuration (give the value from there, relative = 0)"
                )
            load = _load(model, value, 1)
            model.dirichlet.append((nodes, [AXES[p["dof"].text]], load, name, model.window))
        elif kind in ("zero shell displacement", "prescribed shell displacement"):
            from tissuesim.febio.shells import read_shell_bc  # the shells' back faces

            read_shell_bc(model, bc, _node_set(model, bc))
        elif kind == "rigid":  # the node set moves with a rigid body
            from tissuesim.febio.rigid.conditions import read_rigid_nodes

            if model.window is not None:
                raise bc.error(
                    "a rigid interface inside a <step>: tissuesim links nodes to a rigid body "
                    "for the whole run (give it in the model's <Boundary>)"
                )
            from tissuesim.febio.shells import clamped_set  # shells: their back nodes too

            read_rigid_nodes(model, bc, clamped_set(model, bc, _node_set(model, bc)))
        elif kind == "linear constraint":  # febio/linear_constraints.py
            from tissuesim.febio.linear_constraints import read_linear_constraint

            read_linear_constraint(model, bc)
        else:
            raise bc.error(
                f"boundary condition type {kind!r} is not supported by tissuesim; it runs "
                "'zero displacement' (or 'fix'), 'prescribed displacement', 'linear constraint' "
                "and 'rigid'"
            )


def _loads(model: FebModel, section: Node) -> None:
    for load in section.children:
        kind = load.attrib.get("type", "")
        if load.tag == "nodal_load" and kind == "nodal_force":
            nodes = _node_set(model, load)
            p = _children(load, {"value", "relative", "shell_bottom"})
            if "relative" in p and _flag(p["relative"]):
                raise _unsupported(p["relative"], "relative = 1")
            if "shell_bottom" in p and _flag(p["shell_bottom"]):  # on the shells' back faces
                from tissuesim.febio.shells import back_set

                nodes = back_set(model, p["shell_bottom"], nodes)
            if "value" not in p:
                raise load.error("needs a <value> (the force vector)")
            model.nodal.append((nodes, _load(model, p["value"], 3)))
        elif load.tag == "nodal_load" and kind == "nodal_load":  # FEBio 3: one dof, scale
            nodes = _node_set(model, load)
            p = _children(load, {"dof", "scale", "relative"})
            if "dof" not in p or p["dof"].text not in AXES or "scale" not in p:
                raise load.error("needs <dof> x, y or z and a <scale>")
            one = _load(model, p["scale"], 1)
            value = np.zeros(3)
            value[AXES[p["dof"].text]] = one.value[0]
            model.nodal.append((nodes, Load(value, one.curve, model.window)))
        elif load.tag == "surface_load" and kind in ("pressure", "traction"):
            _surface_load(model, load, kind)
        elif load.tag == "surface_load" and kind == "force":  # febio/load_fields.py
            from tissuesim.febio.load_fields import surface_force

            surface_force(model, load)
        elif load.tag == "body_load" and kind == "non-const":  # FEBio 3: math of X, Y, Z, t
            from tissuesim.febio.load_fields import field_body_force

            field_body_force(model, load)
        elif load.tag == "body_load" and kind == "const":  # FEBio 3: x, y, z
            p = _children(load, {"x", "y", "z"})
            curves = {_int_attr(c, "lc", "a load curve id") for c in p.values()}
            value = np.array([_floats(p[a], 1)[0] if a in p else 0.0 for a in "xyz"])
            if len(curves) <= 1:
                curve = curves.pop() if curves else None
                model.body_loads.append(_body_force(Load(value, curve, model.window)))
                continue
            for k, a in enumerate("xyz"):  # a curve per component: a load per component
                if a in p and value[k] != 0.0:
                    part = np.zeros(3)
                    part[k] = value[k]
                    curve = _int_attr(p[a], "lc", "a load curve id")
                    model.body_loads.append(_body_force(Load(part, curve, model.window)))
        elif load.tag == "body_load" and kind == "body force":  # FEBio 4: force vector
            p = _children(load, {"force"})
            if "force" not in p:
                raise load.error("needs a <force> (per unit mass)")
            model.body_loads.append(_body_force(_load(model, p["force"], 3)))
        else:
            raise load.error(
                f"<{load.tag}> type {kind!r} is not supported by tissuesim; it runs nodal_load "
                "('nodal_force', 'nodal_load'), surface_load ('pressure', 'traction' with "
                "<linear>1</linear>, 'force') and body_load ('const', 'body force', 'non-const')"
            )
        if "elem_set" in load.attrib:
            raise _unsupported(load, "a body load on an element set")


def _body_force(load: Load) -> Load:
    """The force per unit mass a FEBio body load applies: the negative of the vector given
    (FEElasticSolidDomain::BodyForce adds -rho f to FEBio's external force, so f = (0, 0,
    9.81) is gravity along -z)."""
    return Load(-load.value, load.curve, load.window)


def _surface_load(model: FebModel, load: Node, kind: str) -> None:
    surface = load.attrib.get("surface")
    if surface not in model.surfaces:
        raise load.error(f"no Surface named {surface!r}")
    if kind == "pressure":
        p = _children(load, {"pressure", "linear", "symmetric_stiffness", "shell_bottom"})
        value = p.get("pressure")
    else:
        p = _children(load, {"traction", "scale", "linear", "shell_bottom"})
        value = p.get("traction")
    if value is None:
        raise load.error(f"needs a <{kind}>")
    if "shell_bottom" in p and _flag(p["shell_bottom"]):
        raise _unsupported(p["shell_bottom"], "shell_bottom = 1")
    if not ("linear" in p and _flag(p["linear"])):
        if kind == "pressure":  # a follower pressure: an energy on a closed surface of
            # triangles, lagged on any other (energies/pressure.py, energies/pressure_lag.py)
            model.tractions.append((surface, "follower", _load(model, value, 1)))
            if "symmetric_stiffness" in p:
                model.note(
                    p["symmetric_stiffness"],
                    "not used: tissuesim gives a follower pressure on a closed surface its "
                    "exact energy and lags one on an open surface (each solve a dead load's)",
                )
            return
        raise p.get("linear", load).error(
            "a traction on the deformed surface (FEBio's default, <linear>0</linear>) is not "
            "supported by tissuesim: write <linear>1</linear> for a dead load on the reference "
            "surface"
        )
    if "symmetric_stiffness" in p:
        model.note(p["symmetric_stiffness"], "not used: a dead pressure has no load stiffness")
    if kind == "pressure":
        model.tractions.append((surface, "pressure", _load(model, value, 1)))
        return
    vector = _load(model, value, 3)
    if "scale" in p:
        scale = _load(model, p["scale"], 1)
        if scale.curve is not None and vector.curve is not None:
            raise p["scale"].error("a curve on both <traction> and <scale>")
        vector = Load(vector.value * scale.value[0], scale.curve or vector.curve, model.window)
    model.tractions.append((surface, "traction", vector))


def _load_data(model: FebModel, section: Node) -> None:
    for lc in section.children:
        if lc.tag not in ("load_controller", "loadcurve"):
            raise _unsupported(lc, "expected <load_controller>")
        kind = lc.attrib.get("type", "loadcurve")
        if kind != "loadcurve":
            raise lc.error(f"load controller type {kind!r}: tissuesim reads 'loadcurve' only")
        if lc.tag == "loadcurve":  # FEBio 2.5 style inside 3.0 files: <point> children
            p = {"points": lc}
        else:
            p = _children(lc, {"interpolate", "extend", "points"})
        interpolate = p["interpolate"].text.upper() if "interpolate" in p else "LINEAR"
        if interpolate not in INTERPOLATIONS:
            raise p["interpolate"].error(
                f"interpolate {interpolate!r}: tissuesim writes {', '.join(INTERPOLATIONS)}"
            )
        extend = p["extend"].text.upper() if "extend" in p else "CONSTANT"
        if extend not in ("CONSTANT", "EXTRAPOLATE", "REPEAT", "REPEAT_OFFSET") or (
            extend == "EXTRAPOLATE" and interpolate != "LINEAR"
        ):
            raise p["extend"].error(
                f"extend {extend!r}: tissuesim writes CONSTANT, REPEAT, REPEAT_OFFSET (and "
                "EXTRAPOLATE for LINEAR)"
            )
        if "points" not in p:
            raise lc.error("needs <points>")
        rows = []
        for pt in p["points"].children:
            if pt.tag not in ("pt", "point"):
                raise _unsupported(pt, "expected <pt>t,value</pt>")
            rows.append(_floats(pt, 2))
        points = np.array(rows).reshape(-1, 2)
        if len(points) == 0 or np.any(np.diff(points[:, 0]) <= 0):
            raise p["points"].error("a load curve needs points with increasing times")
        number = _int_attr(lc, "id", "a load curve id")
        model.curves[len(model.curves) + 1 if number is None else number] = Curve(
            points, interpolate, extend
        )


def _contact(model: FebModel, section: Node) -> None:
    for c in section.children:
        kind = c.attrib.get("type", "")
        if c.tag != "contact" or kind not in CONTACT_TYPES + TIED_TYPES:
            raise c.error(
                f"contact type {kind!r} is not supported by tissuesim; it maps "
                f"{', '.join(CONTACT_TYPES + TIED_TYPES)} onto its contact"
            )
        bottoms = {"shell_bottom_primary", "shell_bottom_secondary"}
        allowed = CONTACT_TUNING | {"fric_coeff", "tension", "offset", "plane"} | bottoms
        if kind in TIED_TYPES:  # a tie holds in tension by itself; its search settings
            allowed |= {
                "search_tolerance",
                "offset_shells",
                "max_distance",
                "special",
                "max_traction",
                "snap_tol",
                "gap_offset",
            }
        p = _children(c, allowed)
        item = {"type": kind, "node": c, "friction": 0.0}
        if "fric_coeff" in p:
            item["friction"] = float(_floats(p["fric_coeff"], 1)[0])
        tension = "tension" in p and _flag(p["tension"])
        if tension and kind != "sliding-elastic":  # FEBio's other contacts have no tension
            raise _unsupported(p["tension"], f"tension = 1 on a {kind} contact")
        if tension and item["friction"] != 0.0:
            raise p["tension"].error("tension = 1 with friction: FEBio's sliding-elastic "
                                     "refuses it too; give fric_coeff 0 or tension 0")  # fmt: skip
        for key in sorted(bottoms & set(p)):  # 0: the shells' front faces, as tissuesim's
            if _flag(p[key]):
                raise _unsupported(p[key], f"contact on the shells' back faces ({key} = 1)")
        if kind == "rigid_wall":
            surface = c.attrib.get("surface")
            if surface not in model.surfaces:
                raise c.error(f"no Surface named {surface!r}")
            if "plane" not in p:
                raise c.error("a rigid_wall needs a <plane>a,b,c,d</plane>")
            item["surfaces"] = (surface,)
            item["plane"] = _floats(p["plane"], 4)
            item["offset"] = _load(model, p["offset"], 1) if "offset" in p else Load(np.zeros(1))
        else:
            if "offset" in p and float(_floats(p["offset"], 1)[0]) != 0.0:
                raise _unsupported(p["offset"], "a contact offset")
            if "plane" in p:
                raise _unsupported(p["plane"], "<plane> outside a rigid_wall")
            pair = c.attrib.get("surface_pair")
            if pair not in model.surface_pairs:
                raise c.error(f"no SurfacePair named {pair!r}")
            item["surfaces"] = model.surface_pairs[pair]
        if kind == "sliding-facet-on-facet":  # FEBio ignores its friction (a warning)
            item["friction"] = 0.0
        if kind in TIED_TYPES:
            for key in ("offset_shells", "max_distance", "gap_offset"):
                if key in p and float(_floats(p[key], 1)[0]) != 0.0:
                    raise _unsupported(p[key], f"a tied contact's {key} = {p[key].text.strip()}")
            item["penalty"] = _penalty_settings(kind, c, p)
        elif kind != "rigid_wall":  # FEBio's own enforcement, its friction too
            item["penalty"] = _penalty_settings(kind, c, p)
            item["penalty"].update(_friction_settings(kind, p, item["friction"]))
            if tension:  # FEBio's sliding-elastic: a projecting point pulls as well
                item["penalty"]["tension"] = True
        # a rigid wall's settings are read by constraint_sections.take_rigid_walls
        model.contacts.append(item)


#: FEBio's defaults per contact type: tolerance (FEFacet2FacetSliding, FESlidingInterface:
#: 0.01; FESlidingElasticInterface: 0.1)
_DEFAULT_TOLERANCE = {"sliding-elastic": 0.1}
#: settings that change what FEBio solves and that tissuesim does not do (on = refused)
_PENALTY_REFUSED = {
    "smooth_aug": "smoothed augmentations (smooth_aug = 1)",
    "node_reloc": "node relocation onto the secondary surface (node_reloc = 1)",
    "flip_primary": "flipped surface normals (flip_primary = 1)",
    "flip_secondary": "flipped surface normals (flip_secondary = 1)",
    "update_penalty": "an auto penalty recomputed every step (update_penalty = 1)",
}


def _penalty_settings(kind: str, c: Node, p: dict) -> dict:
    """FEBio's penalty / augmented-Lagrangian settings of a sliding contact, for tissuesim's
    penalty contact (contact/penalty/pair.py)."""
    for key, what in _PENALTY_REFUSED.items():
        if key in p and _flag(p[key]):
            raise _unsupported(p[key], what)
    method = (p["laugon"].text or "").strip().upper() if "laugon" in p else "PENALTY"
    methods = {"0": False, "PENALTY": False, "1": True, "AUGLAG": True}
    if method not in methods:
        raise _unsupported(p["laugon"], f"contact enforcement laugon = {method!r} (tissuesim "
                           "runs PENALTY (0) and AUGLAG (1))")  # fmt: skip

    def number(key: str, default: float) -> float:
        return float(_floats(p[key], 1)[0]) if key in p else default

    penalty = number("penalty", 1.0)
    if penalty <= 0:
        raise p["penalty"].error(f"penalty = {penalty}: give a positive penalty")
    tied = kind in TIED_TYPES
    search = "search_tolerance" if "search_tolerance" in p else "search_tol"
    out = {
        "penalty": penalty,
        "auto_penalty": _flag(p["auto_penalty"]) if "auto_penalty" in p else False,
        "integration": "nodes" if kind.endswith("node-on-facet") else "gauss",
        "area": "current" if kind == "sliding-elastic" else "reference",
        "two_pass": _flag(p["two_pass"]) if "two_pass" in p else False,
        "augmented": methods[method],
        "tolerance": number("tolerance", _DEFAULT_TOLERANCE.get(kind, 0.01)),
        "gap_tolerance": number("gaptol", 0.0),
        "min_augmentations": int(number("minaug", 0)),
        "max_augmentations": int(number("maxaug", 10)),
        "search_tolerance": number(search, 0.01),
    }
    if kind in SPECIAL_CASE_TYPES:  # FEClosestPointProjection::HandleSpecialCases(true)
        out["special_cases"] = True
    if kind == "sliding-elastic" and methods[method]:  # its Augment updates, then checks
        out["keep_last_augmentation"] = True
    if kind == "sticky":  # FEStickyInterface: nodes, tied once within snap_tol
        out.update(sticky=True, integration="nodes", snap_tolerance=number("snap_tol", 0.0),
                   max_traction=number("max_traction", 0.0))  # fmt: skip
    elif tied:
        out["tied"] = True
    return out


def _friction_settings(kind: str, p: dict, mu: float) -> dict:
    """FEBio's Coulomb friction of a sliding contact (contact/penalty/friction.py): the
    sliding-elastic holds stick by its normal penalty; node-on-facet by its ``fric_penalty``,
    with no friction unless both it and ``fric_coeff`` are positive (``FESlidingInterface``)."""
    if mu < 0:
        raise p["fric_coeff"].error(f"fric_coeff = {mu}: give a friction coefficient >= 0")
    if mu == 0 or kind == "sliding-facet-on-facet":
        return {}
    if kind == "sliding-node-on-facet":
        eps_t = float(_floats(p["fric_penalty"], 1)[0]) if "fric_penalty" in p else 0.0
        if eps_t < 0:
            raise p["fric_penalty"].error(f"fric_penalty = {eps_t}: give a penalty >= 0")
        if eps_t == 0:
            return {}
        return {"friction": mu, "friction_penalty": eps_t, "friction_anchor": "contact"}
    return {"friction": mu}


def _globals(model: FebModel, section: Node) -> None:
    for c in section.children:
        if c.tag == "Variables":  # FEBio's global parameters, fem.name in math expressions
            for v in c.children:
                name = v.attrib.get("name")
                if v.tag != "var" or not name or not re.fullmatch(r"[A-Za-z_]\w*", name):
                    raise v.error('expected <var name="a">value</var>')
                model.variables[name] = float(_floats(v, 1)[0])
            continue
        if c.tag != "Constants":
            raise _unsupported(c, "this Globals element is not supported by tissuesim")
        model.note(c, "physical constants (T, R, Fc, ...) are not used by solid mechanics")


def _output(model: FebModel, section: Node) -> None:
    for c in section.children:
        if c.tag == "logfile":
            from tissuesim.febio.logfiles import read_logfile

            read_logfile(model, c)
            continue
        if c.tag != "plotfile":
            raise _unsupported(c, "this Output element is not supported by tissuesim")
        model.note(c, "FEBio's own output file is not written: tissuesim writes its VTU series "
                   "(displacement, J, stress, strain), forces.csv and summary.json")  # fmt: skip


SECTIONS = {
    "Boundary": _boundary,
    "Loads": _loads,
    "LoadData": _load_data,
    "Contact": _contact,
    "Globals": _globals,
    "Output": _output,
}
