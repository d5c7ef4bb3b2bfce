"""FEBio's ``<Material>`` section: the elastic laws with FEBio's parameters, the fibre laws
with their ``<mat_axis>`` and ``<fiber>``, the ``solid mixture`` / ``uncoupled solid mixture``
of ``<solid>`` components (each a law of its own, with its own directions), and the
``viscoelastic`` / ``uncoupled viscoelastic`` wrappers around an ``<elastic>`` law; and the
per-element directions of ``<MeshData>`` (``ElementData`` of type ``mat_axis`` or ``fiber``).

Directions follow FEBio: a law's local axes Q = [e1 e2 e3] come from ``mat_axis``
(``vector``: e1 = a/|a|, e3 = a x d/|a x d|, e2 = e3 x e1; ``local``: a and d from element
nodes n1 -> n2 and n1 -> n3, default 1, 2, 4; none: the global axes). Holzapfel-Gasser-Ogden
puts its fibres in the plane of e1 and e2; trans iso Mooney-Rivlin's ``fiber`` (default
1,0,0) is given in the local axes, so its global direction is Q fiber. Element data replace
the material's axes (``mat_axis``) or its fibre (``fiber``, a global direction) on the
elements they list. A mixture's component takes its axes as FEBio does, Q = Q_mixture Q_own
(``GetLocalCS``), and FEBio's fibre laws (``fiber-exp-pow``, ``fiber-pow-linear``,
``fiber-exp-linear``) their ``fiber`` in those axes (``type="vector"`` or ``"angles"``: theta,
phi in degrees, (cos theta sin phi, sin theta sin phi, cos phi)); they are read as mixture
components only."""

from __future__ import annotations

import re

import numpy as np

from tissuesim.febio.materials.axes import (
    MixtureOrientation,
    Orientation,
    _direction,
    axes_from,
    body_directions,
    read_mesh_data,
    with_directions,
)
from tissuesim.febio.materials.curve_values import checked_values, curve_value
from tissuesim.febio.materials.distributions import PARTS, check_adaptive_axes, read_part
from tissuesim.febio.materials.expressions import GENERIC, generic_hyperelastic
from tissuesim.febio.materials.growth import kinematic_growth
from tissuesim.febio.materials.laws import (
    ACTIVE,
    CONTINUOUS,
    CURVE_PARAMETERS,
    DAMAGE,
    FIBRE_TYPES,
    FIBRES_ONLY,
    MATERIAL_TYPES,
    MIXTURES,
    NO_ENERGY,
    REACTIVE_VISCOELASTIC,
    UNCOUPLED,
    VECTOR_PARAMETERS,
    VISCOELASTIC,
)
from tissuesim.febio.materials.multigeneration import multigeneration
from tissuesim.febio.materials.prestrain import prestrain_elastic
from tissuesim.febio.model import FebModel, _floats, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = [
    "MATERIAL_TYPES",
    "UNCOUPLED",
    "FIBRE_TYPES",
    "MIXTURES",
    "Orientation",
    "MixtureOrientation",
    "read_materials",
    "read_mesh_data",
    "axes_from",
    "body_directions",
    "with_directions",
]


def read_materials(model: FebModel, node: Node) -> None:
    """<Material>: each <material> checked by building the tissuesim law once."""
    for mat in node.children:
        if mat.tag != "material":
            raise _unsupported(mat, "expected <material>")
        spec = _law(model, mat, top=True)
        name = mat.attrib.get("name") or mat.attrib.get("id", "")
        model.materials[name] = spec
        if "id" in mat.attrib:
            model.materials.setdefault(f"#{mat.attrib['id']}", spec)


def _law(
    model: FebModel,
    mat: Node,
    top: bool,
    component: bool = False,
    bulk: bool = True,
    check: bool = True,
) -> tuple:
    """(model name, parameters, density, FEBio type, Orientation or None); ``component``: a
    solid mixture's ``<solid>`` (not built alone: an uncoupled mixture's component has no k);
    ``bulk`` False: its ``<k>`` and ``<pressure_model>`` left out (an uncoupled mixture's
    component, whose bulk term FEBio ignores)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    kind = mat.attrib.get("type", "")
    if kind == "rigid body" and top:
        from tissuesim.febio.rigid.conditions import rigid_material

        return rigid_material(model, mat)
    if kind in VISCOELASTIC and top:
        return _viscoelastic(model, mat, kind)
    if kind == "kinematic growth" and top:
        return kinematic_growth(model, mat, _law)
    if kind == "prestrain elastic" and top:
        return prestrain_elastic(model, mat, _law)
    if kind == "multigeneration" and top:
        return multigeneration(model, mat, _law)
    if kind in DAMAGE:
        return _damage(model, mat, kind, component, bulk)
    if kind == "reactive viscoelastic damage" and top:
        return _rve_damage(model, mat)
    if kind in REACTIVE_VISCOELASTIC and top:
        return _reactive_viscoelastic(model, mat, kind)
    if kind in MIXTURES:
        if component:
            raise mat.error(f"{kind!r}: a mixture is not a component of a mixture (nor in FEBio)")
        return _mixture(model, mat, kind)
    if kind in GENERIC:
        params, density = generic_hyperelastic(model, mat, kind)
        if not (density > 0.0):
            raise mat.error(f"density {density:g}: a density must be > 0 (kg/m^3 in SI units)")
        if not component:
            try:
                make_material("energy", **params)
            except TissueSimError as exc:
                raise mat.error(f"material {kind!r}: {exc}") from None
        return ("energy", params, density, kind, None)
    if kind not in MATERIAL_TYPES or (kind in FIBRES_ONLY | ACTIVE and not component):
        known = [k for k in MATERIAL_TYPES if component or k not in FIBRES_ONLY | ACTIVE]
        known += list(GENERIC)
        known += list(VISCOELASTIC) + list(REACTIVE_VISCOELASTIC) if top else []
        known += ["kinematic growth", "prestrain elastic", "multigeneration"] if top else []
        known += list(DAMAGE)
        known += list(MIXTURES) if not component else []
        where = " in a solid mixture" if component else ""
        alone = (
            " alone (it has no matrix): put it in a solid mixture"
            if kind in FIBRES_ONLY | ACTIVE
            else ""
        )
        if alone:
            raise mat.error(f"material type {kind!r} is read as a mixture's <solid> only{alone}")
        if kind in NO_ENERGY:
            raise mat.error(f"material type {kind!r} is not run by tissuesim: {NO_ENERGY[kind]}, "
                            "and tissuesim minimises an energy in each step")  # fmt: skip
        raise mat.error(
            f"material type {kind!r} is not supported by tissuesim{where}; it runs "
            f"{', '.join(repr(k) for k in known)}"
        )
    model_name, rename = MATERIAL_TYPES[kind]
    params: dict = {}
    density = 1.0
    orientation = Orientation(FIBRE_TYPES[kind]) if kind in FIBRE_TYPES else None
    _once(mat)
    for p in mat.children:
        if p.tag in ("mat_axis", "fiber") and orientation is not None:
            _direction(orientation, p, kind)
            continue
        if kind in CONTINUOUS and p.tag in PARTS:
            params[p.tag] = read_part(model, p, _law)
            continue
        if p.tag in NO_ENERGY:
            raise p.error(f"<{p.tag}> of {kind!r} is not run by tissuesim: {NO_ENERGY[p.tag]}, "
                          "and tissuesim minimises an energy in each step")  # fmt: skip
        if "lc" in p.attrib and p.tag in CURVE_PARAMETERS.get(kind, ()):
            params[p.tag] = curve_value(p)
            continue
        if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
            raise _unsupported(p, "a material parameter that is a field, a curve or a table")
        if p.tag == "density":
            density = _density(p)
            continue
        if p.tag in ("k", "pressure_model") and not bulk:
            continue
        if p.tag == "pressure_model":
            params[p.tag] = int(p.text) if p.text.isdigit() else p.text
            continue
        key = p.tag if rename is None else rename.get(p.tag)
        if key is None:
            raise p.error(f"parameter {p.tag!r} of {kind!r}: it takes {sorted(rename)}")
        if p.tag in VECTOR_PARAMETERS.get(kind, ()):
            params[key] = _floats(p).tolist()
            continue
        params[key] = float(_floats(p, 1)[0])
    if not component and check:  # (an uncoupled viscoelastic's law: once its k is added)
        try:
            make_material(model_name, **params)
        except TissueSimError as exc:
            raise mat.error(f"material {kind!r}: {exc}") from None
    return (model_name, params, density, kind, orientation)


def _mixture(model: FebModel, mat: Node, kind: str) -> tuple:
    """FEBio's (uncoupled) solid mixture: its ``<solid>`` components, each read as a law of its
    own, an optional ``<mat_axis>`` that turns every component's axes, the uncoupled mixture's
    ``<k>`` and ``<pressure_model>``, and its ``<density>`` (the components' are not used)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    params: dict = {}
    density, axis, components, parts = 1.0, Orientation("axes"), [], []
    seen: dict[str, Node] = {}
    for p in mat.children:
        if p.tag == "solid":
            bulk = kind != "uncoupled solid mixture"
            name, comp, _, _, orientation = _law(model, p, top=False, component=True, bulk=bulk)
            components.append({"model": name, **comp})
            parts.append(orientation)
            continue
        if p.tag in seen:
            raise p.error(f"<{p.tag}> is given twice in <{mat.tag}> (first at line "
                          f"{seen[p.tag].line}): keep one")  # fmt: skip
        seen[p.tag] = p
        if p.tag == "mat_axis":
            _direction(axis, p, kind)
            continue
        if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
            raise _unsupported(p, "a material parameter that is a field, a curve or a table")
        if p.tag == "density":
            density = _density(p)
        elif p.tag == "pressure_model" and kind == "uncoupled solid mixture":
            params[p.tag] = int(p.text) if p.text.isdigit() else p.text
        elif p.tag == "k" and kind == "uncoupled solid mixture":
            params["k"] = float(_floats(p, 1)[0])
        else:
            takes = "<solid>, <mat_axis>, <density>"
            takes += ", <k>, <pressure_model>" if kind == "uncoupled solid mixture" else ""
            raise p.error(f"parameter {p.tag!r} of {kind!r}: it takes {takes}")
    if not components:
        raise mat.error(f"a {kind!r} needs at least one <solid>")
    check_adaptive_axes(mat, axis.axis, parts, components)
    params["components"] = components
    try:
        make_material(MIXTURES[kind], **checked_values(params))
    except TissueSimError as exc:
        raise mat.error(f"material {kind!r}: {exc}") from None
    orientation = None
    if axis.axis is not None or any(o is not None for o in parts):
        orientation = MixtureOrientation(axis.axis, parts)
    return (MIXTURES[kind], params, density, kind, orientation)


def _density(p: Node) -> float:
    """A material's <density>, > 0 (a scene refuses any other, so convert must not write it)."""
    density = float(_floats(p, 1)[0])
    if not density > 0.0:
        raise p.error(f"density {density:g}: a density must be > 0 (kg/m^3 in SI units)")
    return density


def _viscoelastic(model: FebModel, mat: Node, kind: str) -> tuple:
    """FEBio's (uncoupled) viscoelastic: g0, g1..g6, t1..t6 around an <elastic> law; an
    uncoupled wrapper's own k adds to its elastic law's (FEBio sums them)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    g = [0.0] * 6
    tau = [1.0] * 6  # FEBio's defaults: g_i = 0, t_i = 1
    g0, k, density, elastic = 1.0, 0.0, 1.0, None
    _once(mat)
    for p in mat.children:
        if p.tag == "elastic":
            if elastic is not None:
                raise p.error("a second <elastic>")
            # FEBio's uncoupled wrapper adds its k to its law's, which may be 0 alone
            elastic = (_law(model, p, top=False, check=kind != "uncoupled viscoelastic"), p)
            continue
        if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
            raise _unsupported(p, "a material parameter that is a field, a curve or a table")
        if p.tag == "pressure_model" and kind == "uncoupled viscoelastic":
            if p.text.strip() not in ("default", "0"):  # FEBio's default: its elastic law's
                raise p.error(
                    f"pressure_model {p.text.strip()!r} on the {kind!r} wrapper: tissuesim "
                    "takes its elastic law's (give it there)"
                )
            continue
        value = float(_floats(p, 1)[0])
        if p.tag == "density":
            density = _density(p)
        elif p.tag == "g0":
            g0 = value
        elif p.tag == "k" and kind == "uncoupled viscoelastic":
            k = value
        elif len(p.tag) == 2 and p.tag[0] in "gt" and p.tag[1] in "123456":
            (g if p.tag[0] == "g" else tau)[int(p.tag[1]) - 1] = value
        else:
            raise p.error(f"parameter {p.tag!r} of {kind!r}: it takes g0, g1..g6, t1..t6"
                          + (", k" if kind == "uncoupled viscoelastic" else ""))  # fmt: skip
    if elastic is None:
        raise mat.error(f"a {kind!r} material needs an <elastic> law")
    (base, base_params, base_density, base_kind, orientation), where = elastic
    base_params = dict(base_params)
    if k:
        if "k" not in base_params:
            raise where.error(f"{base_kind!r} has no bulk modulus k to add the wrapper's k to")
        base_params["k"] += k
    used = [i for i in range(6) if g[i] != 0.0]
    params = {
        "elastic": {"model": base, **base_params},
        "g": [g[i] for i in used] or [0.0],
        "tau": [tau[i] for i in used] or [1.0],
        "g0": g0,
    }
    if "density" not in {c.tag for c in mat.children}:
        density = base_density
    try:
        make_material(VISCOELASTIC[kind], **params)
    except TissueSimError as exc:
        raise mat.error(f"material {kind!r}: {exc}") from None
    return (VISCOELASTIC[kind], params, density, kind, orientation)


def _damage_table(p: Node) -> dict:
    """A <damage type="CDF ..."> or <criterion type="DC ..."> with its numbers."""
    table: dict = {"model": p.attrib.get("type", "")}
    _once(p)
    for q in p.children:
        if q.children or "lc" in q.attrib or q.attrib.get("type") not in (None, "const"):
            raise _unsupported(q, "a damage parameter that is a field, curve or table")
        table[q.tag] = float(_floats(q, 1)[0])
    return table


def _damage(model: FebModel, mat: Node, kind: str, component: bool, bulk: bool) -> tuple:
    """FEBio's (uncoupled) elastic damage: an <elastic> law, a <damage> CDF ("CDF log-normal",
    ...) and a <criterion> ("DC von Mises stress", ...), each with its parameters; read alone
    or as a solid mixture's <solid> (then its elastic law is read as a component too)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    density, elastic, parts, own = 1.0, None, {}, {}
    _once(mat)
    for p in mat.children:
        if p.tag == "elastic":
            if elastic is not None:
                raise p.error("a second <elastic>")
            uc = kind == "uncoupled elastic damage"  # the law's deviatoric part: its k unused
            read = _law(model, p, top=False, component=component or uc, bulk=bulk and not uc)
            elastic = (read, p)
        elif p.tag in ("damage", "criterion"):
            if p.tag in parts:
                raise p.error(f"a second <{p.tag}>")
            parts[p.tag] = _damage_table(p)
        elif p.tag == "density":
            density = _density(p)
        elif p.tag in ("k", "pressure_model") and kind == "uncoupled elastic damage":
            if bulk:  # its own bulk term (a mixture's component: the mixture's)
                text = p.text.strip()
                value = float(_floats(p, 1)[0]) if p.tag == "k" else text
                own[p.tag] = int(text) if text.isdigit() else value
        else:
            uc = ", <k>, <pressure_model>" if kind == "uncoupled elastic damage" else ""
            raise p.error(f"parameter {p.tag!r} of {kind!r}: it takes <elastic>, <damage>, "
                          f"<criterion>, <density>{uc}")  # fmt: skip
    for need in ("elastic", "damage", "criterion"):
        if need == "elastic" and elastic is None or need != "elastic" and need not in parts:
            raise mat.error(f"a {kind!r} material needs a <{need}>")
    (base, base_params, base_density, _, orientation), _ = elastic
    params = {"elastic": {"model": base, **base_params}, **parts, "density": base_density, **own}
    if "density" not in {c.tag for c in mat.children}:
        density = base_density
    try:
        make_material(DAMAGE[kind], **params)
    except TissueSimError as exc:
        raise mat.error(f"material {kind!r}: {exc}") from None
    return (DAMAGE[kind], params, density, kind, orientation)


def _k2_function(p: Node, variable: str = "K2", what: str = "relaxation") -> object:
    """A ``-dist-user`` relaxation's parameter, a function of K2 (or a recruitment's function of
    X: ``variable``): a number, ``type="math"`` (FEBio's syntax: ^ for powers, ln, log10 as
    log; its free variable named ``variable``) or ``type="point"`` (a curve of it)."""
    from tissuesim.febio.curves import curve_expression
    from tissuesim.febio.model import Curve

    kind = p.attrib.get("type", "const")
    if kind == "math":
        math_nodes = [c for c in p.children if c.tag == "math"]
        text = (math_nodes[0].text if math_nodes else p.text).strip()
        text = re.sub(r"\blog\(", "log10(", text).replace("^", "**")
        if variable != "K2":  # FEBio's free variable, whatever its name (x, X)
            text = re.sub(r"\b[xX]\b", variable, text)
        return re.sub(r"\bln\(", "log(", text)
    if kind == "point":
        interpolate, points = "LINEAR", []
        for c in p.children:
            if c.tag == "interpolate":
                interpolate = c.text.strip().upper()
            elif c.tag == "points":
                points = [_floats(q, 2) for q in c.children]
            elif c.tag != "extend" or c.text.strip().upper() != "CONSTANT":
                raise _unsupported(c, f"a {what} curve setting other than CONSTANT extend")
        if interpolate not in ("LINEAR", "STEP", "SMOOTH") or len(points) < 1:
            raise _unsupported(p, f"a {what} curve with {interpolate} interpolation")
        curve = Curve(np.array(points, dtype=float), interpolate, "CONSTANT")
        return re.sub(r"\bt\b", variable, curve_expression(curve))
    if p.children or "lc" in p.attrib or kind != "const":
        raise _unsupported(p, f"a {what} parameter of this type")
    return float(_floats(p, 1)[0])


def _relaxation(node: Node) -> dict:
    """<relaxation type="relaxation-..."> as tissuesim's table: numbers, Prony's g1..g6 and
    t1..t6 as lists (its terms with g = 0 dropped), the -dist-user functions of K2."""
    kind = node.attrib.get("type", "")
    table: dict = {"model": kind}
    prony = {"g": [0.0] * 6, "t": [1.0] * 6}
    _once(node)
    for p in node.children:
        if kind.endswith("dist-user"):
            table[p.tag] = _k2_function(p)
        elif kind == "relaxation-Prony" and len(p.tag) == 2 and p.tag[1] in "123456":
            prony[p.tag[0]][int(p.tag[1]) - 1] = float(_floats(p, 1)[0])
        else:
            if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
                raise _unsupported(p, "a relaxation parameter that is a field, curve or table")
            table[p.tag] = float(_floats(p, 1)[0])
    if kind == "relaxation-Prony":
        used = [i for i in range(6) if prony["g"][i] != 0.0]
        table["g"] = [prony["g"][i] for i in used]
        table["t"] = [prony["t"][i] for i in used]
    return table


def _recruitment(node: Node) -> dict:
    """<recruitment type="recruitment ..."> as tissuesim's table (materials/reactive/
    recruitment.py): numbers, and the user function of X (a number, math or point curve)."""
    kind = node.attrib.get("type", "")
    table: dict = {"model": kind.removeprefix("recruitment ").strip()}
    _once(node)
    for p in node.children:
        if kind == "recruitment user" and p.tag == "function":
            table["function"] = _k2_function(p, "X", "recruitment")
            continue
        if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
            raise _unsupported(p, "a recruitment parameter that is a field, curve or table")
        table[p.tag] = float(_floats(p, 1)[0])
    return table


def _reactive_viscoelastic(model: FebModel, mat: Node, kind: str) -> tuple:
    """FEBio's (uncoupled) reactive viscoelastic: <elastic> (strong bonds), <bond> (weak
    bonds), <relaxation>, <recruitment> and wmin, kinetics, trigger, emin (and the uncoupled
    one's k, pressure_model: its bulk term; the laws' own k are not used)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    uc = kind == "uncoupled reactive viscoelastic"
    laws: dict = {}
    params: dict = {}
    density = None
    _once(mat)
    for p in mat.children:
        if p.tag in ("elastic", "bond"):
            if p.tag in laws:
                raise p.error(f"a second <{p.tag}>")
            laws[p.tag] = (_law(model, p, top=False, component=uc, bulk=not uc), p)
        elif p.tag == "relaxation":
            params["relaxation"] = _relaxation(p)
        elif p.tag == "recruitment":
            params["recruitment"] = _recruitment(p)
        elif p.tag == "density":
            density = _density(p)
        elif p.tag in ("wmin", "kinetics", "trigger", "emin") or (uc and p.tag == "k"):
            if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
                raise _unsupported(p, "a material parameter that is a field, a curve or a table")
            params[p.tag] = float(_floats(p, 1)[0])
        elif uc and p.tag == "pressure_model":
            params[p.tag] = int(p.text) if p.text.strip().isdigit() else p.text.strip()
        else:
            more = ", k, pressure_model" if uc else ""
            raise p.error(
                f"parameter {p.tag!r} of {kind!r}: it takes <elastic>, <bond>, <relaxation>, "
                "<recruitment>, "
                f"wmin, kinetics, trigger, emin, density{more}"
            )
    for need in ("elastic", "bond", "relaxation"):
        if need not in laws and need not in params:
            raise mat.error(f"a {kind!r} material needs a <{need}>")
    (base, base_params, base_density, _, orientation), _ = laws["elastic"]
    (bond, bond_params, _, _, bond_orientation), where = laws["bond"]
    if bond_orientation is not None:
        raise _unsupported(where, "a bond law with fibre directions")
    params["elastic"] = {"model": base, **base_params}
    params["bond"] = {"model": bond, **bond_params}
    try:
        make_material(REACTIVE_VISCOELASTIC[kind], **params)
    except TissueSimError as exc:
        raise mat.error(f"material {kind!r}: {exc}") from None
    return (REACTIVE_VISCOELASTIC[kind], params, density or base_density, kind, orientation)


def _rve_damage(model: FebModel, mat: Node) -> tuple:
    """FEBio's reactive viscoelastic damage: (1 - D) times a <viscoelastic type="reactive
    viscoelastic">, D of <damage> and <criterion> on its strong bonds' law; read as the reactive
    viscoelastic law with an elastic damage as <elastic> (which scales strong and weak bonds by
    the same 1 - D: FEBio's two definitions agree)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    inner, parts, density = None, {}, None
    _once(mat)
    for p in mat.children:
        if p.tag == "viscoelastic" and p.attrib.get("type") == "reactive viscoelastic":
            if inner is not None:
                raise p.error("a second <viscoelastic>")
            inner = _reactive_viscoelastic(model, p, "reactive viscoelastic")
        elif p.tag in ("damage", "criterion") and p.tag not in parts:
            parts[p.tag] = _damage_table(p)
        elif p.tag == "density":
            density = _density(p)
        else:
            raise p.error(f"parameter {p.tag!r} of 'reactive viscoelastic damage': it takes one "
                          "<viscoelastic type=\"reactive viscoelastic\">, <damage>, <criterion>, "
                          "density")  # fmt: skip
    if inner is None or len(parts) < 2:
        raise mat.error("a 'reactive viscoelastic damage' material needs <viscoelastic type="
                        "\"reactive viscoelastic\">, <damage> and <criterion>")  # fmt: skip
    name, params, inner_density, _, orientation = inner
    damaged = {"model": "elastic_damage", "elastic": params["elastic"], **parts}
    params = {**params, "elastic": {**damaged, "density": inner_density}}
    try:
        make_material(name, **params)
    except TissueSimError as exc:
        raise mat.error(f"material 'reactive viscoelastic damage': {exc}") from None
    return (name, params, density or inner_density, "reactive viscoelastic damage", orientation)
