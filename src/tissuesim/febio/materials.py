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

from dataclasses import dataclass

import numpy as np

from tissuesim.febio.model import FebModel, _floats, _int_attr, _ints, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = [
    "MATERIAL_TYPES",
    "UNCOUPLED",
    "FIBRE_TYPES",
    "MIXTURES",
    "Orientation",
    "read_materials",
]

#: FEBio material types tissuesim runs -> (model, FEBio parameter -> tissuesim keyword; None:
#: the law takes FEBio's parameter names as they are)
MATERIAL_TYPES = {
    "neo-Hookean": ("neo_hookean", {"E": "youngs_modulus", "v": "poisson_ratio"}),
    "isotropic elastic": ("stvk", {"E": "youngs_modulus", "v": "poisson_ratio"}),
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
            "fiber-exp-pow",
            "fiber-exp-pow-uncoupled",
            "fiber-pow-linear",
            "fiber-pow-linear-uncoupled",
        )
    },
    **{
        name: (name, {"c3": "c3", "c4": "c4", "c5": "c5", "lambda": "lam_max"})
        for name in ("fiber-exp-linear", "uncoupled fiber-exp-linear")
    },
}
#: FEBio's fibre laws, read as components of a solid mixture only (they have no matrix)
FIBRES_ONLY = {
    "fiber-exp-pow", "fiber-exp-pow-uncoupled", "fiber-pow-linear", "fiber-pow-linear-uncoupled",
    "fiber-exp-linear", "uncoupled fiber-exp-linear",
}  # fmt: skip
#: FEBio's solid mixtures -> tissuesim's model
MIXTURES = {"solid mixture": "solid_mixture", "uncoupled solid mixture": "uncoupled_solid_mixture"}
#: the fibre laws: FEBio type -> what their directions are ("axes": e1, e2; "fiber": Q fiber)
FIBRE_TYPES = {
    "Holzapfel-Gasser-Ogden": "axes",
    "HGO unconstrained": "axes",
    "trans iso Mooney-Rivlin": "fiber",
    **{name: "fiber" for name in FIBRES_ONLY},
}
#: the uncoupled laws, which FEBio runs with its three-field (mean dilatation) hex8 / tet10
UNCOUPLED = {
    "Mooney-Rivlin", "Ogden", "Yeoh", "Veronda-Westmann", "Arruda-Boyce",
    "Holzapfel-Gasser-Ogden", "trans iso Mooney-Rivlin", "uncoupled viscoelastic",
    "uncoupled solid mixture", "fiber-exp-pow-uncoupled", "fiber-pow-linear-uncoupled",
    "uncoupled fiber-exp-linear",
}  # fmt: skip
VISCOELASTIC = {"viscoelastic": "viscoelastic", "uncoupled viscoelastic": "uncoupled_viscoelastic"}


@dataclass
class Orientation:
    """A fibre law's directions as the model gives them on the material: ``axis`` None
    (global axes), ("vector", a, d) or ("local", (i, j, k)) 0-based element nodes; ``fiber``
    the local fibre (trans iso Mooney-Rivlin)."""

    kind: str
    axis: tuple | None = None
    fiber: np.ndarray | None = None


@dataclass
class MixtureOrientation:
    """A solid mixture's ``mat_axis`` (as ``Orientation.axis``) and, per component, its
    Orientation (None: a law without directions)."""

    axis: tuple | None
    parts: list


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
    model: FebModel, mat: Node, top: bool, component: bool = False, bulk: bool = True
) -> tuple:
    """(model name, parameters, density, FEBio type, Orientation or None); ``component``: a
    solid mixture's ``<solid>`` (not built alone: an uncoupled mixture's component has no k);
    ``bulk`` False: its ``<k>`` and ``<pressure_model>`` left out (an uncoupled mixture's
    component, whose bulk term FEBio ignores)."""
    from tissuesim.errors import TissueSimError
    from tissuesim.materials import make_material

    kind = mat.attrib.get("type", "")
    if kind == "rigid body" and top:
        from tissuesim.febio.rigid import rigid_material

        return rigid_material(model, mat)
    if kind in VISCOELASTIC and top:
        return _viscoelastic(model, mat, kind)
    if kind in MIXTURES:
        if component:
            raise mat.error(f"{kind!r}: a mixture is not a component of a mixture (nor in FEBio)")
        return _mixture(model, mat, kind)
    if kind not in MATERIAL_TYPES or (kind in FIBRES_ONLY and not component):
        known = [k for k in MATERIAL_TYPES if component or k not in FIBRES_ONLY]
        known += list(VISCOELASTIC) if top else []
        known += list(MIXTURES) if not component else []
        where = " in a solid mixture" if component else ""
        alone = (
            " alone (it has no matrix): put it in a solid mixture" if kind in FIBRES_ONLY else ""
        )
        if alone:
            raise mat.error(f"material type {kind!r} is read as a mixture's <solid> only{alone}")
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
        params[key] = float(_floats(p, 1)[0])
    if not component:
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
    params["components"] = components
    try:
        make_material(MIXTURES[kind], **params)
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


def _direction(orientation: Orientation, p: Node, kind: str) -> None:
    """<mat_axis type="vector"|"local"> or <fiber type="vector"> of a fibre law."""
    how = p.attrib.get("type", "vector")
    if p.tag == "mat_axis":
        if how == "vector":
            parts = _once(p)
            if set(parts) != {"a", "d"}:
                raise p.error('a mat_axis type="vector" needs <a> and <d>')
            a, d = _floats(parts["a"], 3), _floats(parts["d"], 3)
            if np.linalg.norm(np.cross(a, d)) <= 1e-12 * np.linalg.norm(a) * np.linalg.norm(d):
                raise p.error("mat_axis: a and d must not be parallel (or zero)")
            orientation.axis = ("vector", a, d)
        elif how == "local":
            nodes = _ints(p) if p.text else [0, 0, 0]
            if len(nodes) != 3 or min(nodes) < 0:
                raise p.error('a mat_axis type="local" lists three element nodes, e.g. 1,2,4')
            if nodes == [0, 0, 0]:
                nodes = [1, 2, 4]
            orientation.axis = ("local", tuple(n - 1 for n in nodes), p)
        else:
            raise p.error(
                f'mat_axis type {how!r} is not supported by tissuesim; it reads "vector" and '
                '"local" (and per-element <ElementData type="mat_axis">)'
            )
        return
    if orientation.kind != "fiber":
        raise p.error(f"{kind!r} takes its fibres from <mat_axis> (e1, e2 and gamma), not <fiber>")
    if how == "angles":  # FEBio's FESphericalAnglesVectorGenerator, degrees
        parts = _once(p)
        if not set(parts) <= {"theta", "phi"}:
            extra = next(c for c in p.children if c.tag not in ("theta", "phi"))
            raise _unsupported(extra, 'a fiber type="angles" takes <theta> and <phi>')
        theta = np.radians(float(_floats(parts["theta"], 1)[0])) if "theta" in parts else 0.0
        phi = np.radians(float(_floats(parts["phi"], 1)[0])) if "phi" in parts else np.pi / 2
        s, c = np.sin(phi), np.cos(phi)
        orientation.fiber = np.array([np.cos(theta) * s, np.sin(theta) * s, c])
        return
    if how != "vector":
        raise p.error(
            f'fiber type {how!r} is not supported by tissuesim; it reads type="vector" and '
            '"angles" (and per-element <ElementData type="fiber">)'
        )
    vector = p.find("vector")
    extra = [c for c in p.children if c.tag != "vector"]
    if extra:
        raise _unsupported(extra[0], "this child of <fiber> is not supported by tissuesim")
    f = _floats(vector if vector is not None else p, 3)
    if not np.linalg.norm(f) > 0.0:
        raise p.error("fiber must be a non-zero vector")
    orientation.fiber = f


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
            elastic = (_law(model, p, top=False), p)
            continue
        if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
            raise _unsupported(p, "a material parameter that is a field, a curve or a table")
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


def read_mesh_data(model: FebModel, section: Node) -> None:
    """<MeshData>: <ElementData type|var="mat_axis"|"fiber" elem_set=...> with one <e lid=...>
    (or <elem lid=...>) per element of the set."""
    for data in section.children:
        if data.tag != "ElementData":
            raise _unsupported(data, "this MeshData element is not supported by tissuesim")
        kind = data.attrib.get("type") or data.attrib.get("var")
        if kind not in ("mat_axis", "fiber"):
            raise data.error(
                f"element data {kind!r} is not supported by tissuesim; it reads 'mat_axis' and "
                "'fiber'"
            )
        members = _element_set(model, data)
        store = model.element_data.setdefault(kind, {})
        for e in data.children:
            if e.tag not in ("e", "elem") or "lid" not in e.attrib:
                raise _unsupported(e, "expected <e lid=...>")
            lid = _int_attr(e, "lid", "an element's local id")
            if not 1 <= lid <= len(members):
                raise e.error(f"lid {lid} is outside the element set (1..{len(members)})")
            if kind == "fiber":
                value = _floats(e, 3)
                if not np.linalg.norm(value) > 0.0:
                    raise e.error("a fiber must be a non-zero vector")
            else:
                parts = _once(e)
                if set(parts) != {"a", "d"}:
                    raise e.error("a mat_axis entry needs <a> and <d>")
                a, d = _floats(parts["a"], 3), _floats(parts["d"], 3)
                if np.linalg.norm(np.cross(a, d)) <= 1e-12 * np.linalg.norm(a) * np.linalg.norm(d):
                    raise e.error("mat_axis: a and d must not be parallel (or zero)")
                value = (a, d)
            store[members[lid - 1]] = (value, e)


def _element_set(model: FebModel, data: Node) -> list:
    """The (part, row) members of the ElementSet or part an ElementData names."""
    name = data.attrib.get("elem_set")
    if name in model.element_sets:
        return list(model.element_sets[name][0])
    if name in model.parts:
        return [(name, r) for r in range(len(model.parts[name][1]))]
    raise data.error(f"no ElementSet or part named {name!r}")


def axes_from(a: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(..., 3, 3) local axes Q = [e1 e2 e3] (columns) from FEBio's a and d."""
    e1 = a / np.linalg.norm(a, axis=-1, keepdims=True)
    e3 = np.cross(a, d)
    e3 /= np.linalg.norm(e3, axis=-1, keepdims=True)
    return np.stack([e1, np.cross(e3, e1), e3], axis=-1)


def body_directions(
    model: FebModel, spec: tuple, parts: list[str], points: np.ndarray, cells: np.ndarray
) -> dict:
    """The direction keys of a body's fibre law (``mat_axis_a``/``mat_axis_d`` or ``fiber``):
    one vector when they are the same in every element, else one per cell (lists). A solid
    mixture's are ``{"components": [keys of each component]}`` (``with_directions``)."""
    orientation = spec[4]
    if orientation is None:
        if any(model.element_data.get(k) for k in ("mat_axis", "fiber")):
            for kind, store in model.element_data.items():
                for (part, _), (_, e) in store.items():
                    if part in parts:
                        raise e.error(f"{kind} data on elements whose law ({spec[3]!r}) has no "
                                      "fibres")  # fmt: skip
        return {}
    if isinstance(orientation, MixtureOrientation):
        for kind, store in model.element_data.items():
            for (part, _), (_, e) in store.items():
                if part in parts:
                    raise _unsupported(
                        e,
                        f"{kind} element data on a {spec[3]!r} (its components "
                        "take their directions from their own mat_axis and fiber)",
                    )
        outer = _axes(orientation.axis, points, cells)
        return {
            "components": [
                {} if o is None else _keys(o, outer @ _axes(o.axis, points, cells), None)
                for o in orientation.parts
            ]
        }
    m = len(cells)
    Q = _axes(orientation.axis, points, cells)
    offsets, start = {}, 0
    for p in parts:
        offsets[p] = start
        start += len(model.parts[p][1])
    given = np.full((m, 3), np.nan)
    for (part, row), ((a, d), _) in model.element_data.get("mat_axis", {}).items():
        if part in offsets:
            Q[offsets[part] + row] = axes_from(a, d)
    for (part, row), (f, e) in model.element_data.get("fiber", {}).items():
        if part in offsets:
            if orientation.kind != "fiber":
                raise e.error(f"{spec[3]!r} takes its fibres from mat_axis, not fiber data")
            given[offsets[part] + row] = f
    return _keys(orientation, Q, given)


def _axes(axis: tuple | None, points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """(m, 3, 3) local axes per cell of an Orientation's ``axis``."""
    m = len(cells)
    if axis is None:
        return np.broadcast_to(np.eye(3), (m, 3, 3)).copy()
    if axis[0] == "vector":
        return np.broadcast_to(axes_from(axis[1], axis[2]), (m, 3, 3)).copy()
    i, j, k = axis[1]
    if max(axis[1]) >= cells.shape[1]:
        raise axis[2].error(f"mat_axis local nodes {[n + 1 for n in axis[1]]}: the "
                            f"elements have {cells.shape[1]} nodes")  # fmt: skip
    x = points[cells]
    a, d = x[:, j] - x[:, i], x[:, k] - x[:, i]
    if np.any(np.linalg.norm(np.cross(a, d), axis=1) == 0.0):
        raise axis[2].error("mat_axis local: three nodes of an element are collinear")
    return axes_from(a, d)


def _keys(orientation: Orientation, Q: np.ndarray, given: np.ndarray | None) -> dict:
    """The law's direction keys from its axes Q (m, 3, 3): e1, e2 of Q, or Q fiber; ``given``
    (m, 3): global fibres from element data (NaN rows: none)."""
    m = len(Q)
    if orientation.kind == "axes":
        keys = {"mat_axis_a": Q[:, :, 0], "mat_axis_d": Q[:, :, 1]}
    else:
        fiber = np.tile(orientation.fiber if orientation.fiber is not None else [1.0, 0, 0], (m, 1))
        local = np.einsum("mij,mj->mi", Q, fiber / np.linalg.norm(fiber, axis=1, keepdims=True))
        if given is not None:
            local = np.where(np.isnan(given[:, :1]), local, given)
        keys = {"fiber": local}
    out = {}
    for key, rows in keys.items():
        rows = np.round(rows, 15) + 0.0
        same = np.allclose(rows, rows[0], rtol=0.0, atol=1e-14)
        out[key] = rows[0].tolist() if same else rows.tolist()
    return out


def with_directions(params: dict, directions: dict) -> dict:
    """A law's parameters with its ``body_directions``: into its ``elastic`` law (a
    viscoelastic wrapper) or its ``components`` (a solid mixture), else its own."""
    params = dict(params)
    if "elastic" in params:
        params["elastic"] = with_directions(params["elastic"], directions)
    elif "components" in directions:
        params["components"] = [
            {**c, **d} for c, d in zip(params["components"], directions["components"], strict=True)
        ]
    else:
        params.update(directions)
    return params
