"""The directions of FEBio's anisotropic laws: a material's ``<mat_axis>`` and ``<fiber>``
(``Orientation``), a solid mixture's (``MixtureOrientation``), the per-element directions of
``<MeshData>`` (``ElementData`` of type ``mat_axis`` or ``fiber``), and a body's direction keys
(``body_directions``) put into its law's parameters (``with_directions``). The conventions are
in ``materials.py``'s docstring."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.febio.model import FebModel, _floats, _int_attr, _ints, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = [
    "Orientation",
    "MixtureOrientation",
    "read_mesh_data",
    "axes_from",
    "body_directions",
    "with_directions",
]


@dataclass
class Orientation:
    """A fibre law's directions as the model gives them on the material: ``axis`` None
    (global axes), ("vector", a, d) or ("local", (i, j, k)) 0-based element nodes; ``fiber``
    the local fibre (trans iso Mooney-Rivlin)."""

    kind: str
    axis: tuple | None = None
    fiber: np.ndarray | None = None
    #: ``<fiber type="local">``: (i, j, node) 0-based element nodes, the fibre n_i -> n_j
    fiber_nodes: tuple | None = None
    #: ``<fiber type="user">``: the node; every element takes its fibre from element data
    user: Node | None = None


@dataclass
class MixtureOrientation:
    """A solid mixture's ``mat_axis`` (as ``Orientation.axis``) and, per component, its
    Orientation (None: a law without directions)."""

    axis: tuple | None
    parts: list


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
        elif how == "angles":  # FEBio's FEMat3dSphericalAngleMap: Q = [a b c], degrees
            parts = _once(p)
            if not set(parts) <= {"theta", "phi"}:
                extra = next(c for c in p.children if c.tag not in ("theta", "phi"))
                raise _unsupported(extra, 'a mat_axis type="angles" takes <theta> and <phi>')
            the = np.radians(float(_floats(parts["theta"], 1)[0])) if "theta" in parts else 0.0
            phi = np.radians(float(_floats(parts["phi"], 1)[0])) if "phi" in parts else np.pi / 2
            a = np.array([np.cos(the) * np.sin(phi), np.sin(the) * np.sin(phi), np.cos(phi)])
            b = np.array([-np.sin(the), np.cos(the), 0.0])  # e2; e3 = a x b = c
            orientation.axis = ("vector", a, b)
        elif how == "local":
            nodes = _ints(p) if p.text else [0, 0, 0]
            if len(nodes) != 3 or min(nodes) < 0:
                raise p.error('a mat_axis type="local" lists three element nodes, e.g. 1,2,4')
            if nodes == [0, 0, 0]:
                nodes = [1, 2, 4]
            orientation.axis = ("local", tuple(n - 1 for n in nodes), p)
        else:
            raise p.error(
                f'mat_axis type {how!r} is not supported by tissuesim; it reads "vector", '
                '"angles" and "local" (and per-element <ElementData type="mat_axis">)'
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
    if how == "local":  # FEBio's FELocalVectorGenerator: element nodes n1 -> n2, default 1, 2
        source = p.find("local") or p
        nodes = _ints(source) if source.text else [0, 0]
        if len(nodes) != 2 or min(nodes) < 0:
            raise p.error('a fiber type="local" lists two element nodes, e.g. <local>1,2</local>')
        if nodes == [0, 0]:
            nodes = [1, 2]
        if min(nodes) == 0 or nodes[0] == nodes[1]:
            raise p.error(f"fiber local nodes {nodes}: two different element nodes from 1")
        orientation.fiber_nodes = (nodes[0] - 1, nodes[1] - 1, p)
        return
    if how == "user":  # FEBio's FEUserVectorGenerator: the fibres are element data
        orientation.user = p
        return
    if how != "vector":
        raise p.error(
            f'fiber type {how!r} is not supported by tissuesim; it reads type="vector", '
            '"angles", "local" and "user" (per-element <ElementData type="fiber">)'
        )
    vector = p.find("vector")
    extra = [c for c in p.children if c.tag != "vector"]
    if extra:
        raise _unsupported(extra[0], "this child of <fiber> is not supported by tissuesim")
    f = _floats(vector if vector is not None else p, 3)
    if not np.linalg.norm(f) > 0.0:
        raise p.error("fiber must be a non-zero vector")
    orientation.fiber = f


def read_mesh_data(model: FebModel, section: Node) -> None:
    """<MeshData>: <ElementData type|var="mat_axis"|"fiber" elem_set=...> with one <e lid=...>
    (or <elem lid=...>) per element of the set."""
    for data in section.children:
        if data.tag != "ElementData":
            raise _unsupported(data, "this MeshData element is not supported by tissuesim")
        kind = data.attrib.get("type") or data.attrib.get("var")
        if kind is None and "name" in data.attrib:
            _element_map(model, data)
            continue
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


#: a named map's data_type -> the numbers each element gives
MAP_SIZES = {"scalar": 1, "vec3": 3, "mat3": 9}


def _element_map(model: FebModel, data: Node) -> None:
    """<ElementData name=... elem_set=... [data_type="scalar"|"vec3"|"mat3"]>: a map that a
    material parameter names (``<F0 type="map">name</F0>``)."""
    kind = data.attrib.get("data_type", "scalar")
    if kind not in MAP_SIZES:
        raise data.error(f"data_type {kind!r}: tissuesim reads {', '.join(MAP_SIZES)} maps")
    members = _element_set(model, data)
    values = {}
    for e in data.children:
        if e.tag not in ("e", "elem") or "lid" not in e.attrib:
            raise _unsupported(e, "expected <e lid=...>")
        lid = _int_attr(e, "lid", "an element's local id")
        if not 1 <= lid <= len(members):
            raise e.error(f"lid {lid} is outside the element set (1..{len(members)})")
        values[members[lid - 1]] = _floats(e, MAP_SIZES[kind])
    model.element_maps[data.attrib["name"]] = (data, values)


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
                {}
                if o is None
                else _keys(o, outer @ _axes(o.axis, points, cells), None, points, cells)
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
    return _keys(orientation, Q, given, points, cells)


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


def _keys(
    orientation: Orientation,
    Q: np.ndarray,
    given: np.ndarray | None,
    points: np.ndarray,
    cells: np.ndarray,
) -> dict:
    """The law's direction keys from its axes Q (m, 3, 3): e1, e2 of Q, or Q fiber; ``given``
    (m, 3): global fibres from element data (NaN rows: none). A ``local`` fibre is its element's
    nodes n_i -> n_j (rest positions); a ``user`` one must be given on every element."""
    m = len(Q)
    if orientation.kind == "axes":
        keys = {"mat_axis_a": Q[:, :, 0], "mat_axis_d": Q[:, :, 1]}
    else:
        if orientation.user is not None and (given is None or np.isnan(given).any()):
            raise orientation.user.error(
                "fiber type 'user': every element of the material needs its fibre in "
                '<MeshData> <ElementData type="fiber"> (a solid mixture\'s component takes none)'
            )
        fiber = np.tile(orientation.fiber if orientation.fiber is not None else [1.0, 0, 0], (m, 1))
        if orientation.fiber_nodes is not None:
            i, j, node = orientation.fiber_nodes
            if max(i, j) >= cells.shape[1]:
                raise node.error(f"fiber local nodes {[i + 1, j + 1]}: the elements have "
                                 f"{cells.shape[1]} nodes")  # fmt: skip
            fiber = points[cells[:, j]] - points[cells[:, i]]
            if np.any(np.linalg.norm(fiber, axis=1) == 0.0):
                raise node.error("fiber local: two nodes of an element coincide")
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
