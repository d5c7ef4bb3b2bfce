"""A FEBio model (``FebModel``) as a tissuesim scene: the TOML tables and one mesh file per
body, so that ``tissuesim run model.feb`` and ``tissuesim run`` on the converted scene build
the same objects (``run`` converts into a temporary directory and loads that scene:
``scene/loader.py load_febio``)."""

from __future__ import annotations

import re

import numpy as np

from tissuesim.errors import InputError
from tissuesim.febio.constraint_sections import rigid_wall_tables
from tissuesim.febio.contact_scene import contact_tables
from tissuesim.febio.curves import load_expression as _times
from tissuesim.febio.discrete import spring_tables
from tissuesim.febio.initial import initial_velocity
from tissuesim.febio.linear_constraints import linear_constraint_tables
from tissuesim.febio.logfiles import cell_rows, logfile_tables
from tissuesim.febio.materials import body_directions, with_directions
from tissuesim.febio.materials.curve_values import resolve_curve_values
from tissuesim.febio.model import FebModel, Load
from tissuesim.febio.reader import UNCOUPLED
from tissuesim.febio.rigid.scene import (
    RIGID_SET,
    interface_sets,
    rigid_bodies,
    rigid_joints,
    rigid_material_of,
    rigid_names,
)
from tissuesim.febio.shells import check_thickness
from tissuesim.febio.surface_owners import facet_owners
from tissuesim.febio.time_stepper import adaptive_table, run_steps

__all__ = ["febio_scene", "scene_bodies"]

INTEGRATORS = {"static": "quasistatic", "dynamic": "newmark"}


def _bodies(model: FebModel) -> list[dict]:
    """Parts joined by shared nodes or discrete springs make one body (one cell type; parts of
    other materials or domain formulations its ``regions``, each its parts, material,
    formulation and rows of the body's cells); the parts of a rigid body material make one
    body of their own (``rigid`` its material), whatever nodes
    they share (febio/rigid/scene.py)."""
    rigid = {p: rigid_material_of(model, p) for p in model.parts}
    names = [p for p in model.parts if rigid[p] is None]
    owner = np.full(len(model.nodes), -1)
    parent = list(range(len(names)))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    for i, name in enumerate(names):
        nodes = np.unique(model.parts[name][1])
        for j in np.unique(owner[nodes][owner[nodes] >= 0]):
            parent[root(int(j))] = root(i)
        owner[nodes] = i
    for spring in model.springs:  # parts a discrete spring joins make one body too: the
        pairs, _ = model.discrete_sets[spring["set"]]  # springs join vertices of one body
        for a, b in owner[pairs]:
            if a >= 0 and b >= 0 and root(int(a)) != root(int(b)):
                parent[root(int(a))] = root(int(b))
    groups: dict[int, list[str]] = {}
    for i, name in enumerate(names):
        groups.setdefault(root(i), []).append(name)
    bodies = []
    thin = check_thickness(model)  # rigid shells of no thickness: no FEM body (shells.py)
    for material in dict.fromkeys(m for m in rigid.values() if m is not None):
        own = [p for p, m in rigid.items() if m == material and p not in thin]
        if own:
            groups[-1 - len(groups)] = own
    for parts in groups.values():
        first = model.parts[parts[0]][3]
        types = {model.parts[p][0] for p in parts}
        if len(types) > 1:
            raise first.error(
                f"parts {parts} share nodes (or discrete springs) but mix element types "
                f"{sorted(types)}: the regions of one tissuesim body share one cell type (join "
                "them with a tie)"
            )
        cells = np.vstack([model.parts[p][1] for p in parts])
        # one region per (material, domain formulation): cells of one material each
        keys = [(_material_of(model, p), model.domains[p][1]) for p in parts]
        order = list(dict.fromkeys(keys))
        sizes = [len(model.parts[p][1]) for p in parts]
        label = np.repeat([order.index(k) for k in keys], sizes)
        whole = rigid[parts[0]] is not None  # a rigid body is one body, whatever its pieces
        rows = [np.arange(len(cells))] if whole else _pieces(model, parts, cells)
        for piece in rows:
            present = [k for k in range(len(order)) if (label[piece] == k).any()]
            material, formulation = order[present[0]]
            body = {
                "parts": parts,
                "material": material,
                "cell_type": next(iter(types)),
                "cells": cells[piece],
                "formulation": formulation,
                "node": first,
                "rigid": rigid[parts[0]],
            }
            if len(present) > 1:  # several materials on shared nodes: one body of regions
                body["regions"] = [
                    {
                        "parts": [p for p, key in zip(parts, keys, strict=True) if key == order[k]],
                        "material": order[k][0],
                        "formulation": order[k][1],
                        "rows": np.flatnonzero(label[piece] == k),
                    }
                    for k in present
                ]
            bodies.append(body)
    return bodies


def _pieces(model: FebModel, parts: list[str], cells: np.ndarray) -> list[np.ndarray]:
    """The rows of a body's cells split into the pieces that share no node, where pieces meet at
    coincident nodes (FEBio keeps two nodes at one place apart: an unwelded seam is a cut,
    and co01's two blocks in one part touch through contact only); one piece otherwise. A
    split is one line in ``model.changes``."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    used = np.unique(cells)
    X = model.nodes[used]
    tol = 1e-9 * max(float(np.linalg.norm(np.ptp(X, axis=0))), 1e-300)
    _, counts = np.unique(np.round(X / tol), axis=0, return_counts=True)
    if counts.max(initial=1) < 2:
        return [np.arange(len(cells))]
    k = len(cells)
    incidence = sp.csr_matrix(
        (np.ones(cells.size), (np.repeat(np.arange(k), cells.shape[1]), cells.ravel())),
        shape=(k, len(model.nodes)),
    )
    count, label = connected_components(incidence @ incidence.T, directed=False)
    if count < 2:
        return [np.arange(len(cells))]
    node = model.parts[parts[0]][3]
    model.changes.append(
        f"{node.where()}: part(s) {parts} hold {count} pieces that share no node and meet at "
        "coincident nodes (FEBio keeps coincident nodes apart): one body per piece"
    )
    return [np.flatnonzero(label == c) for c in range(count)]


def scene_bodies(model: FebModel) -> list[tuple[str, dict]]:
    """(the scene's name, body) of every body the converter makes: a body is named after its
    first part in a scene of several bodies (or with rigid bodies), else "body"."""
    bodies = _bodies(model)
    if not _several(model, bodies):
        return [("body", b) for b in bodies]
    valid = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
    used = {b["parts"][0] for b in bodies if valid.fullmatch(b["parts"][0])}
    named, taken = [], set()
    for b in bodies:
        part = b["parts"][0]
        # a part split in pieces (_pieces): the first keeps its name, the others ".2", ...
        name = part if valid.fullmatch(part) and part not in taken else body_name(part, used)
        taken.add(name)
        line = (
            f"{b['node'].where()}: part {part!r} is the body {name!r} (a body's name names "
            "its output files: letters, digits, '_', '-' or '.')"
        )
        if name != part and line not in model.changes:  # e.g. FEBio's "Part3(2)"
            model.changes.append(line)
        used.add(name)
        named.append((name, b))
    return named


def body_name(part: str, used: set[str]) -> str:
    """A valid body name for a FEBio part (letters, digits, '_', '-', '.', starting with a
    letter or digit, as ``simulation/bodies.py`` takes): FEBio's name when it is one, else
    its other characters as '_' ("Part3(2)" -> "Part3_2"); unique among ``used`` (then
    ".2", ".3", ...)."""
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", part).strip("_.-") or "part"
    if not name[0].isalnum():
        name = f"part{name}"
    unique, k = name, 2
    while unique in used:
        unique, k = f"{name}.{k}", k + 1
    return unique


def _several(model: FebModel, bodies: list[dict]) -> bool:
    """Whether the scene is one of [[bodies]]: several bodies, or any rigid body (a rigid
    shell of no thickness makes none but is one)."""
    thin = any(rigid_material_of(model, p) is not None for p in model.parts)
    regions = any("regions" in b for b in bodies)  # regions are [[bodies.regions]] tables
    return (
        len(bodies) > 1 or bool(model.rigid_nodes) or any(b["rigid"] for b in bodies) or thin
        or regions
    )  # fmt: skip


def _material_of(model: FebModel, part: str) -> str:
    mat = model.domains[part][0]
    return mat if mat in model.materials else f"#{mat}"


def febio_scene(model: FebModel, stem: str) -> tuple[dict, dict]:
    """(the scene's tables, {mesh file name: Mesh}) for a FEBio model; mesh files are named
    after ``stem`` (one per body)."""
    from tissuesim.mesh.checks import validate_mesh

    check_thickness(model)  # a shell part left without a thickness (febio/shells.py)
    named = scene_bodies(model)  # rigid bodies: [[rigid_bodies]] of a scene of [[bodies]]
    bodies = [b for _, b in named]
    several = _several(model, bodies)
    tables_per_body, meshes, gravity = [], {}, np.zeros(3)
    placed: set[tuple[str, int]] = set()  # the conditions written into some body
    # a surface's facet lying in several bodies is loaded once, as FEBio does (surface_owners)
    owners = {
        set_name: facet_owners(model.nodes, facets, [b["cells"] for b in bodies])
        for set_name, (facets, _) in model.surfaces.items()
    }
    for index, (name, body) in enumerate(named):
        used = np.unique(body["cells"])
        local = np.full(len(model.nodes), -1)
        local[used] = np.arange(len(used))
        point_sets, facet_sets, cell_sets = {}, {}, {}
        body["interfaces"] = interface_sets(model, body, used)
        for rigid_name, nodes in body["interfaces"].items():
            point_sets[RIGID_SET.format(rigid_name)] = local[nodes]
        for set_name, ids in model.node_sets.items():
            mine = local[ids[local[ids] >= 0]]
            if len(mine):
                point_sets[_node_set_name(model, set_name)] = mine
        for set_name, (facets, _) in model.surfaces.items():
            inside = owners[set_name] == index
            if inside.any():
                facet_sets[set_name] = local[facets[inside]]
        for set_name, (members, _) in model.element_sets.items():
            rows = cell_rows(body, members, model)
            if len(rows):
                cell_sets[set_name] = rows
        tables: dict = {}
        for k, (surface, kind, load) in enumerate(model.tractions):
            if surface not in facet_sets:
                continue
            if kind == "traction":
                traction = [_times(load, model, i) for i in range(3)]
                tables.setdefault("traction", []).append(
                    {"facets": {"tagged": surface}, "traction": traction}
                )
                continue
            if kind == "follower":  # FEBio's non-linear pressure (energy or lag: pressure.py)
                tables.setdefault("pressure", []).append(
                    {"facets": {"tagged": surface}, "pressure": _times(load, model, 0)}
                )
                continue
            groups = _by_normal(model.nodes[used], facet_sets[surface], model, surface)
            for g, (normal, rows) in enumerate(groups):
                set_name = surface if len(groups) == 1 else f"{surface}.pressure{k}_{g}"
                facet_sets[set_name] = facet_sets[surface][rows]
                traction = [
                    _times(Load(-load.value[0] * normal, load.curve, load.window), model, i)
                    for i in range(3)
                ]
                tables.setdefault("traction", []).append(
                    {"facets": {"tagged": set_name}, "traction": traction}
                )
        region_sets = {}  # a cell set per region, named after a part; written first (a
        for region in body.get("regions", ()):  # mesh file's cell has one set: they win)
            set_name = f"{body_name(region['parts'][0], set())}.region"
            taken = cell_sets.keys() | point_sets.keys() | facet_sets.keys() | region_sets.keys()
            while set_name in taken:
                set_name = f"{set_name.removesuffix('.region')}_.region"
            region_sets[set_name] = region["rows"]
        cell_sets = {**region_sets, **cell_sets}
        mesh = validate_mesh(
            model.nodes[used],
            local[body["cells"]],
            source=f"{model.source} part {body['parts'][0]}",
            point_sets=point_sets,
            facet_sets=facet_sets,
            cell_sets=cell_sets,
        )
        file = f"{stem}.msh" if not several else f"{stem}.{name}.msh"
        meshes[file] = mesh
        material, density, formulation = _law(
            model, body, body["material"], body["formulation"], body["parts"], body["cells"]
        )
        tables.update(mesh={"file": file}, density=density, formulation=formulation)
        # FEBio integrates a hex8's mass by its 2 x 2 x 2 Gauss points (exact only on
        # parallelepipeds); dy03 and dy04's impacts follow FEBio's iterates only with its mass
        tables["mass"] = "element_rule"
        if "regions" not in body:
            tables["material"] = material
        else:  # parts of other materials on the body's nodes (_bodies)
            tables["regions"] = []
            for region, set_name in zip(body["regions"], region_sets, strict=True):
                law, rho, kind = _law(model, body, region["material"], region["formulation"],
                                      region["parts"], body["cells"][region["rows"]])  # fmt: skip
                tables["regions"].append({"name": set_name.removesuffix(".region"),
                                          "cells": set_name, "material": law,
                                          "formulation": kind, "density": rho})  # fmt: skip
            curved = model.body_force_fields or any(
                load.curve is not None or load.window is not None for load in model.body_loads
            )
            if curved and len({r["density"] for r in tables["regions"]}) > 1:
                raise body["node"].error(
                    f"a body load with a load curve on parts {body['parts']} of different "
                    "densities: tissuesim writes it as a force per volume of one density"
                )
        for k, (nodes, comps, load, bc_name, window) in enumerate(model.dirichlet):
            if _node_set_name(model, nodes) not in mesh.point_sets | mesh.facet_sets:
                continue
            placed.add(("dirichlet", k))
            entry = {"vertices": {"tagged": _node_set_name(model, nodes)}}
            if load is not None:
                displacement = ["0.0"] * 3
                displacement[comps[0]] = _times(load, model, windowed=False)
                entry["displacement"] = displacement
            if comps is not None:
                entry["components"] = comps
            if bc_name:
                entry["name"] = bc_name
            if window is not None:
                entry["active"] = list(window)
            tables.setdefault("dirichlet", []).append(entry)
        for k, (nodes, load) in enumerate(model.nodal):
            if _node_set_name(model, nodes) in mesh.point_sets | mesh.facet_sets:
                placed.add(("nodal", k))
                force = [_times(load, model, i) for i in range(3)]
                tables.setdefault("nodal_forces", []).append(
                    {"vertices": {"tagged": _node_set_name(model, nodes)}, "force": force}
                )
        for load in model.body_loads:
            if load.curve is None and load.window is None:
                gravity += load.value / len(bodies)
            else:
                density_load = Load(density * load.value, load.curve, load.window)
                force = [_times(density_load, model, i) for i in range(3)]
                tables.setdefault("body_force", []).append({"force_density": force})
        for k, expression, load in model.body_force_fields:  # FEBio 3's non-const body load
            force = ["0.0"] * 3
            scaled = Load(density * load.value, load.curve, load.window)
            force[k] = f"{_times(scaled, model)} * ({expression})"
            tables.setdefault("body_force", []).append({"force_density": force})
        j = next(i for i, b in enumerate(bodies) if b is body)
        springs = spring_tables(model, bodies, j, local)  # <Discrete> (febio/discrete.py)
        if springs:
            tables["discrete_springs"] = springs
        constraints = linear_constraint_tables(model, body, local, lambda load: _times(load, model))
        if constraints:  # <bc type="linear constraint"> (febio/linear_constraints.py)
            tables["linear_constraints"] = constraints
        velocity = initial_velocity(model, body)  # <Initial> (febio/initial.py)
        if velocity is not None:
            tables["initial"] = {"velocity": velocity}
        tables_per_body.append((name, tables))
    _unique_support_names(tables_per_body)
    in_bodies = np.unique(np.concatenate([np.ravel(b["cells"]) for b in bodies]))
    _all_placed(model, placed, in_bodies)
    sim = {
        "integrator": INTEGRATORS[model.analysis],
        "time_step": model.step_size,
    }  # FEBio's DYNAMIC: Newmark's method with its beta and gamma
    schemes = {p["newmark"] for p in model.phases if p["newmark"]} or (
        {model.newmark} if model.newmark else set()
    )
    if len(schemes) > 1:
        raise model.phases[0]["node"].error(
            f"DYNAMIC steps with different Newmark parameters {sorted(schemes)}: tissuesim "
            "runs one (beta, gamma) per model"
        )
    if schemes:
        scheme = schemes.pop()
        # (beta, gamma): Newmark's method; (alpha_f, alpha_m, beta, gamma): generalised-alpha
        sim["generalized_alpha" if len(scheme) == 4 else "newmark"] = list(scheme)
    steps = model.phases or [
        {"time_steps": model.time_steps, "step_size": model.step_size, "analysis": model.analysis,
         "time_stepper": model.time_stepper, "plot_level": model.plot_level}
    ]  # fmt: skip
    adaptive = [adaptive_table(model, p["time_stepper"], p["plot_level"]) for p in steps]
    if model.phases or adaptive[0] is not None:  # one phase per <step>; adaptive steps
        sim["integrator"] = INTEGRATORS[steps[0]["analysis"]]
        sim["time_step"] = steps[0]["step_size"]
        sim["phases"] = [
            {"steps": p["time_steps"], "time_step": p["step_size"],
             "integrator": INTEGRATORS[p["analysis"]]}
            for p in steps
        ]  # fmt: skip
        for phase, table in zip(sim["phases"], adaptive, strict=True):
            if table is not None:  # FEBio's time stepper over the step's time
                phase["adaptive"] = table
    if "generalized_alpha" in sim:  # FEBio's DYNAMIC steps with rhoi in [0, 1] or alpha != 1
        for table in [sim, *sim.get("phases", ())]:
            if table["integrator"] == "newmark":
                table["integrator"] = "generalized_alpha"
    data: dict = {}
    if not several:
        ((_, tables),) = tables_per_body
        for key in ("density", "formulation", "mass"):
            sim[key] = tables.pop(key)
        data["simulation"] = sim
        data.update(tables)
    else:
        data["simulation"] = sim
        data["bodies"] = [{"name": name, **tables} for name, tables in tables_per_body]
    if gravity.any():
        data["gravity"] = {"acceleration": (gravity * len(bodies)).tolist()}
    rigid = rigid_bodies(model, bodies, [n for n, _ in tables_per_body],
                         lambda load, m: _times(load, m, windowed=False))  # fmt: skip
    if rigid:
        data["rigid_bodies"] = rigid
    data.update(contact_tables(model, [n for n, _ in tables_per_body], meshes))
    walls = rigid_wall_tables(model, [n for n, _ in tables_per_body], meshes)
    if walls:  # FEBio's rigid walls as FEBio enforces them (febio/constraint_sections.py)
        data["rigid_wall"] = walls
    names = rigid_names(rigid, model)
    joints = rigid_joints(model, names, lambda load, m: _times(load, m, windowed=False))
    if joints:
        data["rigid_joints"] = joints
    logfiles = logfile_tables(model, bodies, [n for n, _ in tables_per_body], names)
    if logfiles:
        data["logfiles"] = logfiles
    data["run"] = {
        "steps": sum(
            run_steps(p["time_steps"], p["step_size"], table)
            for p, table in zip(steps, adaptive, strict=True)
        )
    }
    return data, meshes


def _all_placed(model: FebModel, placed: set[tuple[str, int]], in_bodies: np.ndarray) -> None:
    """Every displacement condition and nodal load on nodes of a body is written into that
    body: one that no body took would be dropped without a word (a shell condition on an
    "@surface:" set was, sh61), so the converter says so instead. (A condition on nodes of no
    element, a spring's anchor, is the springs' to take: febio/discrete.py.)"""
    for kind, entries in (("dirichlet", model.dirichlet), ("nodal", model.nodal)):
        for k, entry in enumerate(entries):
            on_bodies = np.isin(model.node_sets[entry[0]], in_bodies).any()
            if on_bodies and (kind, k) not in placed:
                raise InputError(
                    f"{model.source}: the converter placed the {kind} condition on node set "
                    f"{entry[0]!r} in no body (a converter error: please report it with the "
                    "model)"
                )


def _unique_support_names(tables_per_body: list[tuple[str, dict]]) -> None:
    """A support's name once in the scene (the loader refuses a name given twice): FEBio lets
    two <bc> share a name, and a <bc> on nodes of two bodies is written once per body. The
    first keeps its name, a later one gets its body's name (then a number) as a suffix."""
    used: set[str] = set()
    for body, tables in tables_per_body:
        for entry in tables.get("dirichlet", []):
            name = entry.get("name")
            if name is None:
                continue
            unique, k = name, 1
            while unique in used:
                unique = f"{name}.{body}" if k == 1 else f"{name}.{body}.{k}"
                k += 1
            entry["name"] = unique
            used.add(unique)


def _node_set_name(model: FebModel, name: str) -> str:
    """A node set's name in the mesh file (gmsh names are unique: a node set named like a
    surface gets a suffix). "@surface:name" is every node of the surface's facets, a
    quadratic facet's mid-side nodes included (its facet set holds the corners only)."""
    if name.startswith("@surface:"):
        return f"{name.removeprefix('@surface:')}.surface_nodes"
    return f"{name}.nodes" if name in model.surfaces else name


def _by_normal(points: np.ndarray, facets: np.ndarray, model: FebModel, surface: str):
    """Facets grouped by their unit normal (a dead pressure is one traction per flat group)."""
    x = points[facets]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    if facets.shape[1] == 4:
        off = np.abs(np.einsum("ij,ij->i", x[:, 3] - x[:, 0], n))
        size = np.linalg.norm(x[:, 2] - x[:, 0], axis=1)
        if np.any(off > 1e-9 * size):
            raise model.surfaces[surface][1].error(
                "a pressure on warped quadrilaterals: tissuesim's dead traction needs flat facets"
            )
    keys = np.round(n, 9)
    groups = []
    for key in np.unique(keys, axis=0):
        rows = np.flatnonzero((keys == key).all(axis=1))
        groups.append((n[rows].mean(axis=0), rows))
    if len(groups) > 64:
        raise model.surfaces[surface][1].error(
            f"a pressure on a curved surface ({len(groups)} facet directions): tissuesim's dead "
            "traction is written per flat group of facets, at most 64"
        )
    return groups


def _law(model: FebModel, body: dict, key: str, formulation, parts: list[str], cells):
    """(the material table, density, formulation) of the parts ``parts`` of material ``key``
    on ``cells`` of ``body``: FEBio's three-field default for uncoupled laws on hexahedra,
    tet10 and wedges, fibre directions per cell, curve-valued parameters."""
    spec = model.materials[key]
    model_name, params, density, kind, _ = spec
    if body["rigid"] is not None:  # any law: a rigid motion strains nothing
        model_name = "neo_hookean"
        E, v = params.get("E", 1.0), params.get("v", 0.3)
        params = {"youngs_modulus": E if E > 0 else 1.0,
                  "poisson_ratio": v if -1.0 < v < 0.5 else 0.3}  # fmt: skip
    if formulation is None:
        linear = ("hexahedron", "tetra10", "wedge")  # FEBio's three-field default
        three_field = kind in UNCOUPLED and body["cell_type"] in linear
        formulation = "mean_dilatation" if three_field else "displacement"
    elif formulation == "mean_dilatation" and body["cell_type"] == "tetra":
        raise body["node"].error("three-field-solid on tet4: tissuesim's P1 mean dilatation "
                                 "is a vertex patch, not FEBio's element")  # fmt: skip
    if model_name == "viscoelastic" and formulation == "mean_dilatation":
        raise model.domains[parts[0]][2].error(
            f"{kind!r} on {body['cell_type']} with the three-field element: tissuesim's "
            "coupled viscoelastic law relaxes the volumetric stress too and runs the "
            'displacement form only: give the SolidDomain type="elastic-solid"'
        )
    directions = body_directions(model, spec, parts, model.nodes, cells)
    params = with_directions(params, directions)
    params = resolve_curve_values(params, model, parts)
    return {"model": model_name, **params}, density, formulation
