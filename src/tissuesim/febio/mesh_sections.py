"""FEBio's ``<Mesh>`` (Nodes, Elements, NodeSet, Surface, ElementSet, SurfacePair) and
``<MeshDomains>`` (SolidDomain, ShellDomain) sections, in FEBio 3.0's and 4.0's spellings;
shells (quad4, tri3) become solid parts in ``shells.py``."""

from __future__ import annotations

import numpy as np

from tissuesim.febio.model import FebModel, _floats, _index, _int_attr, _ints, _unsupported
from tissuesim.febio.shells import (
    QUADRATIC_SHELLS,
    SHELL_ELEMENTS,
    add_shell_part,
    check_shared_nodes,
    read_mesh_data,
    read_shell_domain,
    shells_of,
)
from tissuesim.febio.xml import Node

__all__ = ["SECTIONS", "ELEMENTS", "PERMUTATIONS", "FACETS"]

#: FEBio element type -> (nodes per element, meshio's cell type)
ELEMENTS = {
    "tet4": (4, "tetra"),
    "tet10": (10, "tetra10"),
    "hex8": (8, "hexahedron"),
    "hex20": (20, "hexahedron20"),
    "hex27": (27, "hexahedron27"),
    "penta6": (6, "wedge"),
}
#: FEBio element type -> FEBio's local node of each of tissuesim's (VTK's) nodes, where the
#: orders differ: tissuesim's cell = FEBio's element[PERMUTATIONS[type]]. From the reference
#: coordinates of FEBio's nodes (FECore/FESolidElementShape.cpp: FEHex20::shape_fnc, HEX27_LUT):
#: hex8, hex20 and hex27's nodes 0-19 are VTK's; hex27 puts its face centres in the order
#: y = -1, x = +1, y = +1, x = -1, z = -1, z = +1, VTK x = -1, x = +1, y = -1, y = +1, ...
#: penta6 is read as it is: FEPenta6::shape_fnc puts its nodes at (r, s, t) = (0, 0, -1),
#: (1, 0, -1), (0, 1, -1), (0, 0, 1), (1, 0, 1), (0, 1, 1), Gmsh's and meshio's ``wedge`` order,
#: which tissuesim uses (``mesh/cells/wedge.py``; VTK's mirrors it, and meshio converts)
PERMUTATIONS = {"hex27": np.array([*range(20), 23, 21, 20, 22, 24, 25, 26])}
#: FEBio surface facet types -> corners kept (tissuesim's facets are corner lists; FEBio lists
#: a facet's corners first). A surface that mixes triangles and quadrilaterals (a penta6
#: mesh's) keeps its triangles as (a, b, c, c), the rows of 4 a wedge mesh's facets are
#: (``mesh/cells/wedge.py``)
FACETS = {"tri3": 3, "tri6": 3, "quad4": 4, "quad8": 4, "quad9": 4}


def _id_list(model: FebModel, node: Node) -> list[int]:
    """A set's ids: FEBio 4's comma list, or FEBio 3's <n id=.../> / <node id=.../> / <e>."""
    if node.children:
        ids = []
        for c in node.children:
            if c.tag not in ("n", "node", "e", "elem") or "id" not in c.attrib:
                raise _unsupported(c, "expected <n id=...> entries")
            ids.append(_int_attr(c, "id", "an id"))
        return ids
    return _ints(node)


def _edge(model: FebModel, node: Node) -> None:
    """<Edge name=...> of <line2>/<line3> segments: its nodes, the node set "@edge:name" a
    condition names (an edge's loads and contact are not read)."""
    name = node.attrib.get("name")
    if not name:
        raise node.error("an Edge needs a name")
    rows = []
    for c in node.children:
        if c.tag not in ("line2", "line3"):
            raise _unsupported(c, "expected <line2> or <line3> segments")
        rows.append(_index(model, c, _ints(c)))
    if not rows:
        raise node.error("an Edge needs at least one segment")
    model.node_sets[f"@edge:{name}"] = np.unique(np.concatenate(rows))


def read_discrete_set(model: FebModel, node: Node) -> None:
    """<DiscreteSet> (febio/discrete.py)."""
    from tissuesim.febio.discrete import read_discrete_set as read

    read(model, node)


def _mesh(model: FebModel, section: Node) -> None:
    model._node_index = getattr(model, "_node_index", {})
    model._element_index = getattr(model, "_element_index", {})
    for node in section.children:
        handler = MESH_PARTS.get(node.tag)
        if handler is None:
            raise _unsupported(node, "this Mesh element is not supported by tissuesim")
        handler(model, node)


def _nodes(model: FebModel, node: Node) -> None:
    first = len(model.nodes)
    for k, c in enumerate(node.children):
        if c.tag != "node" or "id" not in c.attrib:
            raise _unsupported(c, "expected <node id=...>x,y,z</node>")
        i = _int_attr(c, "id", "a node id")
        if i in model._node_index:
            raise c.error(f"node id {i} is defined twice")
        model._node_index[i] = first + k
    if node.children:
        model.nodes = np.vstack([model.nodes, _coordinates(node.children)])


def _coordinates(nodes: list[Node]) -> np.ndarray:
    """(n, 3) coordinates of <node>s: all parsed at once (a million in a second), and node by
    node only to name the first bad one and its line."""
    texts = [c.text for c in nodes]
    flat = ",".join(texts).replace(";", ",").split(",")
    if len(flat) == 3 * len(nodes) and all(t.count(",") + t.count(";") == 2 for t in texts):
        try:
            values = np.array(flat, dtype=float).reshape(-1, 3)
        except ValueError:
            values = None
        if values is not None and np.isfinite(values).all():
            return values
    return np.array([_floats(c, 3) for c in nodes])


def _elements(model: FebModel, node: Node) -> None:
    kind = node.attrib.get("type", "")
    if kind not in ELEMENTS and kind not in SHELL_ELEMENTS:
        raise node.error(
            f"element type {kind!r} is not supported by tissuesim; it runs "
            f"{', '.join(ELEMENTS)} and the shells {', '.join(SHELL_ELEMENTS)} (penta15, "
            f"pyramids, tet5, tet15, tet20, the quadratic shells {', '.join(QUADRATIC_SHELLS)} "
            "and beams are not)"
        )
    nv, cell_type = ELEMENTS[kind] if kind in ELEMENTS else SHELL_ELEMENTS[kind]
    name = node.attrib.get("name") or f"Part{len(model.parts) + 1}"
    if name in model.parts:
        raise node.error(f"a second <Elements> part named {name!r}")
    ids, elems = [], node.children
    for c in elems:
        if c.tag not in ("elem", kind) or "id" not in c.attrib:
            raise _unsupported(c, f"expected <elem id=...> with {nv} node ids")
        eid = _int_attr(c, "id", "an element id")
        if eid in model._element_index:
            raise c.error(f"element id {eid} is defined twice")
        model._element_index[eid] = (name, len(ids))
        ids.append(eid)
    if not elems:
        raise node.error("no elements in this part")
    cells = _connectivity(model, elems, kind, nv)
    if kind in PERMUTATIONS:
        cells = cells[:, PERMUTATIONS[kind]]
    if kind in ORDERS:
        _check_order(model, kind, cells, elems)
    if kind in SHELL_ELEMENTS:  # a hexahedron / wedge part: the shell's back face added
        cells = add_shell_part(model, name, kind, cells)
    model.parts[name] = (cell_type, cells, np.array(ids), node)
    if "mat" in node.attrib:  # FEBio 2.5 style: the material on the part
        model.domains[name] = (node.attrib["mat"], None, node)


def _connectivity(model: FebModel, elems: list[Node], kind: str, nv: int) -> np.ndarray:
    """(k, nv) 0-based node rows of the elements: all parsed and looked up at once, and
    element by element only to name the first bad one and its line."""
    texts = [c.text for c in elems]
    flat = ",".join(texts).split(",")
    if len(flat) == nv * len(elems) and all(t.count(",") == nv - 1 for t in texts):
        try:
            given = np.array(flat, dtype=np.int64)
        except ValueError:
            given = None
        if given is not None and model._node_index:
            known = np.fromiter(model._node_index, dtype=np.int64, count=len(model._node_index))
            rows = np.fromiter(model._node_index.values(), np.int64, count=len(known))
            order = np.argsort(known)
            at = np.searchsorted(known, given, sorter=order).clip(max=len(known) - 1)
            found = order[at]
            if (known[found] == given).all():
                return rows[found].reshape(-1, nv)
    cells = []
    for c in elems:
        conn = _ints(c)
        if len(conn) != nv:
            raise c.error(f"a {kind} element has {nv} nodes, got {len(conn)}")
        cells.append(_index(model, c, conn))
    return np.array(cells, dtype=np.int64)


#: the node order, in words, of the elements checked as they are read (the quadratic
#: hexahedra and the wedge), for the refusal of a misnumbered one
ORDERS = {
    "hex20": "corners, then the midside nodes of edges 1-2 2-3 3-4 4-1 5-6 6-7 7-8 8-5 1-5 "
    "2-6 3-7 4-8",
    "hex27": "hex20's, then the centres of the faces y-, x+, y+, x-, z-, z+ and the centre",
    "penta6": "the triangle 1-2-3 counter-clockwise seen from the triangle 4-5-6 above it",
}


def _check_order(model: FebModel, kind: str, cells: np.ndarray, elems: list[Node]) -> None:
    """Refuses the first element whose rest map has a Jacobian that is not positive at a Gauss
    point or node: its nodes are not in FEBio's order (or it is folded or inverted)."""
    from tissuesim.mesh.cells.tensor_checks import DEGENERATE, tensor_jacobians

    detJ = tensor_jacobians(model.nodes, cells)
    bad = (detJ <= DEGENERATE * np.abs(detJ).mean(axis=1, keepdims=True)).any(axis=1)
    if bad.any():
        e = int(np.flatnonzero(bad)[0])
        raise elems[e].error(
            f"the Jacobian of this {kind} runs from {detJ[e].min():.3g} to "
            f"{detJ[e].max():.3g} over its Gauss points and nodes ({int(bad.sum())} such "
            f"elements): its nodes are not in FEBio's order ({ORDERS[kind]}), or it "
            "is folded or inverted"
        )


def _node_set(model: FebModel, node: Node) -> None:
    name = node.attrib.get("name")
    if not name:
        raise node.error("a NodeSet needs a name")
    model.node_sets[name] = _index(model, node, _id_list(model, node))


def _surface(model: FebModel, node: Node) -> None:
    name = node.attrib.get("name")
    if not name:
        raise node.error("a Surface needs a name")
    facets, every = [], []
    for c in node.children:
        if c.tag not in FACETS:
            raise c.error(
                f"surface facet type {c.tag!r} is not supported by tissuesim; it reads "
                f"{', '.join(FACETS)}"
            )
        conn = _index(model, c, _ints(c))
        facets.append(conn[: FACETS[c.tag]])
        every.append(conn)
    if not facets:
        raise node.error("a surface needs at least one facet")
    if len({len(f) for f in facets}) > 1:  # a wedge mesh's triangles and quadrilaterals
        from tissuesim.mesh.cells.wedge import as_facets

        facets = as_facets([np.pad(f, (0, 4 - len(f)), mode="edge") for f in facets])
    model.surfaces[name] = (np.array(facets, dtype=np.int64), node)
    model.surface_nodes[name] = np.unique(np.concatenate(every))


def _element_set(model: FebModel, node: Node) -> None:
    name = node.attrib.get("name")
    if not name:
        raise node.error("an ElementSet needs a name")
    ids = _id_list(model, node)
    missing = [i for i in ids if i not in model._element_index]
    if missing:
        raise node.error(f"element id {missing[0]} is not defined in <Elements>")
    model.element_sets[name] = ([model._element_index[i] for i in ids], node)


def _surface_pair(model: FebModel, node: Node) -> None:
    pair = {}
    for c in node.children:
        if c.tag not in ("primary", "secondary", "master", "slave"):
            raise _unsupported(c, "expected <primary> and <secondary>")
        role = {"master": "secondary", "slave": "primary"}.get(c.tag, c.tag)
        if c.text not in model.surfaces:
            raise c.error(f"no Surface named {c.text!r}")
        pair[role] = c.text
    if set(pair) != {"primary", "secondary"}:
        raise node.error("a SurfacePair needs a <primary> and a <secondary> surface")
    model.surface_pairs[node.attrib.get("name", "")] = (pair["primary"], pair["secondary"])


MESH_PARTS = {
    "Nodes": _nodes,
    "Elements": _elements,
    "NodeSet": _node_set,
    "Surface": _surface,
    "ElementSet": _element_set,
    "SurfacePair": _surface_pair,
    "DiscreteSet": read_discrete_set,
    "Edge": _edge,
}

#: SolidDomain type -> tissuesim formulation (None: FEBio's default for the law)
DOMAIN_TYPES = {"elastic-solid": "displacement", "three-field-solid": "mean_dilatation"}


def _mesh_domains(model: FebModel, section: Node) -> None:
    for node in section.children:
        if node.tag == "ShellDomain":
            read_shell_domain(model, node)
            continue
        if node.tag != "SolidDomain":
            raise _unsupported(node, "tissuesim runs solid and shell domains only")
        name, mat = node.attrib.get("name"), node.attrib.get("mat")
        if name not in model.parts:
            raise node.error(f"no <Elements> part named {name!r}")
        if name in shells_of(model).faces:
            raise node.error(f"part {name!r} is made of shells: give it a <ShellDomain>")
        if mat not in model.materials:
            raise node.error(f"no <material> named {mat!r}")
        kind = node.attrib.get("type")
        if kind is not None and kind not in DOMAIN_TYPES:
            raise node.error(f"domain type {kind!r} is not supported by tissuesim")
        extra = set(node.attrib) - {"name", "mat", "type"}
        if extra or node.children:
            what = sorted(extra)[0] if extra else f"<{node.children[0].tag}>"
            raise node.error(f"{what}: domain options are not supported by tissuesim")
        model.domains[name] = (mat, DOMAIN_TYPES.get(kind), node)
    check_shared_nodes(model)  # shells on rigid parts clamped to them, on solids refused


#: "MeshData" here replaces reader.py's entry (``reader.SECTIONS`` spreads these after it):
#: shell thickness data, the rest passed on to ``materials/axes.py read_mesh_data``
SECTIONS = {"Mesh": _mesh, "MeshDomains": _mesh_domains, "MeshData": read_mesh_data}
