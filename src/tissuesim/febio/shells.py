"""FEBio's shells (``quad4``, ``tri3``, ``quad8`` in a ``<ShellDomain>``) as the solids they are.

FEBio 3/4's shell (``FESSIShellDomain``, ``FEElasticShellDomain``: "elastic-shell") gives each
node its displacement u and a second one, w (the DOFs ``sx, sy, sz``), the displacement of
the shell's back face: the point at (r, s, eta) is sum_i M_i(r, s) [(1 + eta)/2 (X_i + u_i) +
(1 - eta)/2 (X_i - D_i + w_i)], D_i the node's director (``FEModel::InitShells``: the mean of
the unit corner normals of the shells around it times their thickness there). Its F is that
map's, its integration 2 x 2 (quad4) or 3 (tri3, (1/6, 1/6), (2/3, 1/6), (1/6, 2/3)) points in
the plane times 2 Gauss points through the thickness, with the solid laws. That is exactly a
hexahedron (a wedge) whose top face is the shell's nodes and whose bottom face is the nodes
moved by -D, with tissuesim's hex8 (wedge) quadrature: so each shell part becomes a
``hexahedron`` (``wedge``) part here, one new node per shell node (its back face, appended to
``model.nodes``), and w is that node's displacement (FEBio's solution vector, and its
``solution_norm``, holds w). ``zero shell displacement`` / ``prescribed shell displacement``
hold the back nodes. The mesh is ``tissuesim.mesh.generators.shells``' (``solid_shell``).
A quad8 shell (FEBio's FEShellQuad8G18: 3 x 3 points in the plane times 2) is a hexahedron20
with the "shell" formulation (``kinematics/shell.py``: quadratic in the plane, linear through
the thickness, the 16 nodes' functions on FEBio's 18 points), one more node halfway through
the thickness at each corner (it carries nothing and is held; it draws the element).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.febio.model import FebModel, Load, _flag, _floats, _int_attr, _once, _unsupported
from tissuesim.febio.xml import Node
from tissuesim.mesh.generators.shells import shell_directors

__all__ = [
    "SHELL_ELEMENTS",
    "add_shell_part",
    "read_shell_domain",
    "read_mesh_data",
    "read_shell_bc",
    "back_set",
    "clamped_set",
]

#: FEBio shell element -> (nodes, the solid it is here)
SHELL_ELEMENTS = {"quad4": (4, "hexahedron"), "tri3": (3, "wedge"), "quad8": (8, "hexahedron20")}
#: FEBio's quadratic shells tissuesim has no solid for (tri6: a 12-node wedge)
QUADRATIC_SHELLS = ("quad9", "tri6", "tri7")
#: ShellDomain type -> formulation (None: FEBio's default for the law: three-field for an
#: uncoupled law on quad4, as tissuesim's hexahedra; tri3 gets "displacement" below)
SHELL_DOMAINS = {
    "elastic-shell": "displacement",
    "three-field-shell": "mean_dilatation",
    "rigid-shell": None,  # FERigidShellDomain: a rigid body material's shells (a rigid body)
}
SHELL_BCS = ("zero shell displacement", "prescribed shell displacement")
AXES = {"sx": 0, "sy": 1, "sz": 2}


@dataclass
class Shells:
    """The model's shell parts: faces (node rows), FEBio element type, thickness per corner,
    and the back node of every shell node."""

    faces: dict = field(default_factory=dict)  # part -> (k, nv) front node rows
    kinds: dict = field(default_factory=dict)  # part -> "quad4" / "tri3"
    thickness: dict = field(default_factory=dict)  # part -> (k, nv)
    back: dict = field(default_factory=dict)  # front node row -> back node row
    #: a quad8 shell's corner node row -> the hexahedron20's midside node between it and its
    #: back node (kinematics/shell.py: it carries nothing, it draws the element)
    middle: dict = field(default_factory=dict)


def shells_of(model: FebModel) -> Shells:
    """The model's Shells (created on first use)."""
    if not hasattr(model, "_shells"):
        model._shells = Shells()  # type: ignore[attr-defined]
    return model._shells  # type: ignore[attr-defined]


def _new_nodes(model: FebModel, table: dict, rows: np.ndarray) -> np.ndarray:
    """``rows`` mapped through ``table`` (front node row -> a new node row), the rows not in
    it yet given new nodes (at their front node until the thickness is read) appended to
    ``model.nodes`` in node order."""
    new = [int(i) for i in np.unique(rows) if int(i) not in table]
    first = len(model.nodes)
    for k, i in enumerate(new):
        table[i] = first + k
    model.nodes = np.vstack([model.nodes, model.nodes[new]])
    return np.vectorize(table.__getitem__, otypes=[np.int64])(rows)


def add_shell_part(model: FebModel, name: str, kind: str, faces: np.ndarray) -> np.ndarray:
    """The solid cells of a shell part: new back nodes appended to ``model.nodes``; (k, 2 nv)
    cells, back face first; a quad8 shell's (k, 20) hexahedron20 cells (VTK's order: back
    corners, front corners, back midsides, front midsides, then a new node halfway along each
    corner's thickness, ``kinematics/shell.py``)."""
    shells = shells_of(model)
    back = _new_nodes(model, shells.back, faces)
    shells.faces[name] = faces
    shells.kinds[name] = kind
    shells.thickness[name] = np.zeros(faces.shape)
    if kind == "quad8":
        middle = _new_nodes(model, shells.middle, faces[:, :4])
        return np.concatenate(
            [back[:, :4], faces[:, :4], back[:, 4:], faces[:, 4:], middle], axis=1
        )
    return np.concatenate([back, faces], axis=1)


def _place(model: FebModel, node: Node) -> None:
    """Back nodes at X - D (FEBio's directors, over every shell part); ``node`` the element
    that gave the thickness, named by a refusal."""
    from tissuesim.errors import MeshError

    shells = shells_of(model)
    if not shells.faces:
        return
    front = np.array(list(shells.back), dtype=np.int64)
    n = len(model.nodes)
    total, count = np.zeros((n, 3)), np.zeros(n)
    for nv in {f.shape[1] for f in shells.faces.values()}:  # quad4, tri3, quad8 parts
        parts = [p for p, f in shells.faces.items() if f.shape[1] == nv]
        faces = np.concatenate([shells.faces[p] for p in parts])
        thickness = np.concatenate([shells.thickness[p] for p in parts])
        try:
            mean = shell_directors(model.nodes, faces, thickness, normalize=False)
        except MeshError as exc:
            raise node.error(str(exc)) from None
        corners = np.bincount(faces.ravel(), minlength=n).astype(float)
        total += mean * corners[:, None]
        count += corners
    directors = total / np.maximum(count, 1.0)[:, None]  # FEModel::InitShells' mean
    model.nodes[[shells.back[i] for i in front.tolist()]] = model.nodes[front] - directors[front]
    if shells.middle:  # quad8: halfway through the thickness
        corner = np.array(list(shells.middle), dtype=np.int64)
        half = model.nodes[corner] - 0.5 * directors[corner]
        model.nodes[[shells.middle[i] for i in corner.tolist()]] = half


def read_shell_domain(model: FebModel, node: Node) -> None:
    """<ShellDomain name mat [type]> with <shell_thickness> (and <shell_normal_nodal>1)."""
    name, mat = node.attrib.get("name"), node.attrib.get("mat")
    shells = shells_of(model)
    if name not in model.parts:
        raise node.error(f"no <Elements> part named {name!r}")
    if name not in shells.faces:
        raise node.error(f"part {name!r} is not made of shell elements (quad4, tri3, quad8)")
    if mat not in model.materials:
        raise node.error(f"no <material> named {mat!r}")
    kind = node.attrib.get("type")
    if kind is not None and kind not in SHELL_DOMAINS:
        raise node.error(
            f"shell domain type {kind!r} is not supported by tissuesim; it runs "
            f"{', '.join(SHELL_DOMAINS)} (the EAS, ANS and old shells are not)"
        )
    extra = sorted(set(node.attrib) - {"name", "mat", "type"})
    if extra:
        raise node.error(f"{extra[0]}: shell domain options are not supported by tissuesim")
    p = _once(node)
    for tag, child in p.items():
        if tag == "shell_normal_nodal":
            if not _flag(child):
                raise _unsupported(child, "shell_normal_nodal = 0 (element normals)")
        elif tag == "laugon" and kind == "three-field-shell":  # FE3FieldElasticShellDomain
            if _flag(child):
                raise _unsupported(child, "laugon = 1 (the augmented three-field shell)")
        elif tag == "secant_stress":  # FEElasticShellDomain: the law's secant stress
            if _flag(child):
                raise _unsupported(child, "secant_stress = 1 (the law's secant stress)")
        elif tag == "secant_tangent":  # only FEBio's Newton tangent: the solution is the same
            model.note(child, "FEBio's Newton tangent (secant or not): the solution is the same")
        elif tag in ("atol", "minaug", "maxaug") and kind == "three-field-shell":
            model.note(child, "the three-field shell's augmentation, off (laugon = 0)")
        elif tag != "shell_thickness":
            raise _unsupported(child, "this ShellDomain parameter is not supported by tissuesim")
    if "shell_thickness" in p:
        h = _floats(p["shell_thickness"], 1)[0]
        if h < 0.0:
            raise p["shell_thickness"].error("a shell thickness must not be negative")
        if h > 0.0:  # FEBio's AssignDefaultShellThickness: 0 leaves it to <MeshData>
            shells.thickness[name][:] = h
            _place(model, node)
    formulation = SHELL_DOMAINS.get(kind) if kind else None
    if shells.kinds[name] == "quad8":  # kinematics/shell.py; FEBio: no three-field by default
        if formulation == "mean_dilatation":
            raise node.error(
                "three-field-shell on quad8 shells is not supported by tissuesim (their "
                "elastic-shell is)"
            )
        formulation = "shell"
    if formulation is None and shells.kinds[name] == "tri3":
        formulation = "displacement"  # FEBio: no three-field tri3 shell by default
    if kind == "rigid-shell" and model.materials[mat][3] != "rigid body":
        raise node.error(
            f"a rigid-shell domain takes a rigid body material, not {model.materials[mat][3]!r}"
        )
    model.domains[name] = (mat, formulation, node)


def check_shared_nodes(model: FebModel) -> None:
    """After <MeshDomains>: a deformable shell node shared with a rigid part moves with the
    rigid body, its back node too (FEBio clamps every deformable shell node's shell DOFs to
    the rigid body it joins: ``FEMechModel``'s RIGID_CLAMP), so the back nodes become a rigid
    node set (``model.rigid_nodes``); a shell sharing nodes with a deformable solid joins it
    as FEBio's shell-solid interface does (``attach_solid``)."""
    from tissuesim.febio.rigid.scene import rigid_material_of

    shells = shells_of(model)
    for name, faces in shells.faces.items():
        if name not in model.domains or rigid_material_of(model, name) is not None:
            continue
        for part, (_, cells, _, _) in model.parts.items():
            if part == name or part not in model.domains:
                continue
            shared = np.intersect1d(cells, faces)
            if not shared.size:
                continue
            body = rigid_material_of(model, part)
            if body is None and part in shells.faces:
                continue  # two deformable shell parts: one back node per node
            node = model.domains[name][2]
            if body is None:
                attach_solid(model, name, part, shared)
                continue
            set_name = f"{name}.{part}.clamped"
            model.node_sets[set_name] = np.array(
                [shells.back[int(i)] for i in shared], dtype=np.int64
            )
            model.rigid_nodes.append((set_name, body, node))


def attach_solid(model: FebModel, name: str, part: str, shared: np.ndarray) -> bool:
    """A deformable solid part sharing the nodes ``shared`` with the shell part ``name``
    (FEBio's ``FESSIShellDomain::FindSSI``): where one of the solid's cells has a whole shell
    element as a face and lies behind the shell (the face's outward normal along the shell's
    normal), the solid is attached to the shell's back face: every shared node of the solid's
    cells is the shell's back node there (FEBio's ``m_bitfc``: the solid takes X - D and the
    shell DOFs w, ``FESolidDomain::GetCurrentNodalCoordinates``), so its cells are renumbered
    to the back nodes. A solid in front of the shell, or touching it along edges only, shares
    the nodes' displacement u as they are. True when the solid was attached to the back."""
    from scipy import sparse

    shells = shells_of(model)
    faces = shells.faces[name]
    cell_type, cells, ids, node = model.parts[part]
    n = len(model.nodes)

    def incidence(rows: np.ndarray) -> sparse.csr_matrix:
        k, nv = rows.shape
        r = np.repeat(np.arange(k), nv)
        return sparse.csr_matrix((np.ones(k * nv), (r, rows.ravel())), shape=(k, n))

    common = (incidence(faces) @ incidence(cells).T).tocoo()
    whole = common.data == faces.shape[1]  # the cell holds every node of the shell element
    e, c = common.row[whole], common.col[whole]
    if not e.size:
        return False
    x = model.nodes
    f = x[faces[e]]
    normal = np.cross(f[:, 1] - f[:, 0], f[:, 2] - f[:, 0])  # the shell's normal (front)
    outward = f.mean(axis=1) - x[cells[c]].mean(axis=1)  # from the cell into the face
    if not ((normal * outward).sum(axis=1) > 0.0).any():
        return False
    back = np.arange(n)
    back[shared] = [shells.back[int(i)] for i in shared]
    model.parts[part] = (cell_type, back[cells], ids, node)
    return True


def read_shell_thickness(model: FebModel, data: Node) -> None:
    """<ElementData type="shell thickness" elem_set=...> (FEBio 3: var=): <e lid=...> one
    thickness per node of the element (or one for all)."""
    from tissuesim.febio.materials.axes import _element_set

    shells = shells_of(model)
    members = _element_set(model, data)
    solid = next((part for part, _ in members if part not in shells.faces), None)
    if solid is not None:
        raise data.error(
            f"element data 'shell thickness' on part {solid!r}, which has no shell elements "
            "(quad4, tri3, quad8)"
        )
    for e in data.children:
        if e.tag not in ("e", "elem") or "lid" not in e.attrib:
            raise _unsupported(e, "expected <e lid=...>")
        lid = _int_attr(e, "lid", "an element's local id")
        if not 1 <= lid <= len(members):
            raise e.error(f"lid {lid} is outside the element set (1..{len(members)})")
        part, row = members[lid - 1]
        nv = shells.faces[part].shape[1]
        values = _floats(e)
        if values.size not in (1, nv) or (values <= 0.0).any():
            raise e.error(f"a shell thickness is 1 or {nv} positive numbers")
        shells.thickness[part][row] = values
    _place(model, data)


def read_mesh_data(model: FebModel, section: Node) -> None:
    """<MeshData>: shell thickness data here, the rest by ``materials/axes.py read_mesh_data``."""
    from tissuesim.febio.materials.axes import read_mesh_data as read_axes

    rest = []
    for data in section.children:
        kind = data.attrib.get("type") or data.attrib.get("var")  # FEBio 3: var=
        if data.tag == "ElementData" and kind == "shell thickness":
            read_shell_thickness(model, data)
        else:
            rest.append(data)
    if rest:
        read_axes(model, Node(section.tag, section.attrib, section.line, section.source,
                              section.text, rest))  # fmt: skip


def check_thickness(model: FebModel) -> set[str]:
    """Refuse a deformable shell part left without a thickness (FEBio: "Zero shell
    thickness"); called by a shell condition and when the scene is built (``febio/scene.py``).
    Returns the rigid shell parts without one (FEBio's ``FERigidShellDomain`` takes them: a
    rigid body of no mass there): they make no FEM body, their nodes still join the rigid
    body (a deformable part's shared nodes are glued to it), a line in ``model.changes``."""
    from tissuesim.febio.rigid.scene import rigid_material_of

    shells = shells_of(model)
    thin = set()
    for name, h in shells.thickness.items():
        if (h <= 0.0).any():
            node = model.domains.get(name, (None, None, model.parts[name][3]))[2]
            body = rigid_material_of(model, name) if name in model.domains else None
            if body is not None and (h <= 0.0).all() and _nominal(model, name, node):
                continue
            if body is not None and (h <= 0.0).all():
                thin.add(name)
                line = (
                    f"{node.where()}: rigid shell part {name!r} has no thickness: no FEM body "
                    f"(no mass); its nodes move with the rigid body {body!r}"
                )
                if line not in model.changes:
                    model.changes.append(line)
                continue
            raise node.error(
                f"shell part {name!r} has no thickness: give <shell_thickness> in its "
                '<ShellDomain> or <ElementData type="shell thickness">'
            )
    return thin


#: the thickness a rigid shell without one is given where it carries a contact surface,
#: relative to its size (its mass plays no part in a static analysis)
NOMINAL_THICKNESS = 1e-3


def _nominal(model: FebModel, name: str, node: Node) -> bool:
    """A rigid shell part without thickness that carries a contact surface (every node of a
    contact's surface on it) in a STATIC analysis, sharing no node with another shell part:
    given NOMINAL_THICKNESS times its size, so that its body (and its surface) exists; a line
    in ``model.changes``. Whether it was."""
    shells = shells_of(model)
    faces = shells.faces[name]
    mine = np.unique(faces)
    others = [f for p, f in shells.faces.items() if p != name]
    if model.analysis != "static" or any(np.intersect1d(f, mine).size for f in others):
        return False
    named = [s for c in model.contacts for s in c.get("surfaces", ()) if s in model.surfaces]
    carried = [s for s in named if np.isin(model.surfaces[s][0], mine).all()]
    if not carried:
        return False
    x = model.nodes[mine]
    h = NOMINAL_THICKNESS * float(np.linalg.norm(x.max(axis=0) - x.min(axis=0)))
    shells.thickness[name][:] = h
    _place(model, node)
    model.changes.append(
        f"{node.where()}: rigid shell part {name!r} has no thickness and carries the contact "
        f"surface {carried[0]!r}: it is given {h:.3g} (its mass plays no part in a static "
        "analysis; FEBio's rigid shell has none)"
    )
    return True


def back_set(model: FebModel, node: Node, nodes: str) -> str:
    """The node set of the back nodes of a set of shell nodes (``<nodes>.back``), for a
    condition on the shells' back faces (``node`` the element that asks, for a refusal)."""
    shells = shells_of(model)
    rows = model.node_sets[nodes]
    missing = [int(i) for i in rows if int(i) not in shells.back]
    if missing:
        raise node.error(f"node set {nodes!r} holds nodes of no shell (row {missing[0]})")
    name = f"{nodes}.back"
    model.node_sets[name] = np.array([shells.back[int(i)] for i in rows], dtype=np.int64)
    return name


def clamped_set(model: FebModel, bc: Node, nodes: str) -> str:
    """A rigid interface (<bc type="rigid">) holds the back nodes of its shell nodes too, as
    FEBio's ``clamp_shells`` (1 by default for its shells) does: the set ``<nodes>.clamped``
    (``nodes`` itself when it holds no shell node or clamp_shells is 0)."""
    shells = shells_of(model)
    clamp = bc.find("clamp_shells")
    if clamp is not None and not _flag(clamp):
        return nodes
    rows = model.node_sets[nodes]
    backs = [shells.back[int(i)] for i in rows if int(i) in shells.back]
    if not backs:
        return nodes
    name = f"{nodes}.clamped"
    model.node_sets[name] = np.concatenate([rows, np.array(backs, dtype=np.int64)])
    return name


def read_shell_bc(model: FebModel, bc: Node, nodes: str) -> None:
    """A <bc> on the shells' back faces: ``zero shell displacement`` (sx_dof, sy_dof, sz_dof)
    or ``prescribed shell displacement`` (dof sx / sy / sz, value, relative = 0)."""
    check_thickness(model)
    back = back_set(model, bc, nodes)
    kind, name = bc.attrib.get("type"), bc.attrib.get("name")
    p = _once(bc)
    if kind == "zero shell displacement":
        allowed = {"sx_dof", "sy_dof", "sz_dof"}
        for c in p.values():
            if c.tag not in allowed:
                raise _unsupported(c, f"this parameter of <{bc.tag}> is not supported")
        comps = [AXES[t[:2]] for t in ("sx_dof", "sy_dof", "sz_dof") if t in p and _flag(p[t])]
        if not comps:
            raise bc.error("fixes no degree of freedom")
        model.dirichlet.append(
            (back, None if comps == [0, 1, 2] else comps, None, name, model.window)
        )
        return
    for c in p.values():
        if c.tag not in ("dof", "value", "relative"):
            raise _unsupported(c, f"this parameter of <{bc.tag}> is not supported")
    if "dof" not in p or p["dof"].text not in AXES or "value" not in p:
        raise bc.error("needs <dof> sx, sy or sz and a <value>")
    if "relative" in p and _flag(p["relative"]) and model.window and model.window[0] > 0.0:
        raise p["relative"].error("relative = 1 in a step after the first")
    curve = _int_attr(p["value"], "lc", "a load curve id")
    load = Load(_floats(p["value"], 1), curve, model.window)
    model.dirichlet.append((back, [AXES[p["dof"].text]], load, name, model.window))
