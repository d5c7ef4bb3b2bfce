"""The tables of one FEM body (top level in a one-body scene, inside each [[bodies]] entry):
[mesh] (a generator, a file or a surface to tetrahedralise), [material], the body options,
supports and loads with their vertex and facet selectors."""

from __future__ import annotations

import difflib
import inspect
from pathlib import Path

import numpy as np

from tissuesim.errors import SceneError
from tissuesim.scene.common import (
    SELECTORS,
    _context,
    _field,
    _material,
    _table,
    _unknown,
    condition,
    of_time,
)
from tissuesim.scene.expressions import compile_vector
from tissuesim.validate import short

__all__ = ["MESH_KEYS", "FEM_BODY_KEYS", "FEM_BODY_OPTIONS", "FEM_TABLE_KEYS", "add_fem_body"]

#: the keys of a FEM body's condition and load tables
FEM_TABLE_KEYS = {
    "dirichlet": {"vertices", "displacement", "components", "name", "active"},
    "traction": {"facets", "traction"},
    "pressure": {"facets", "pressure", "name"},
    "body_force": {"force_density"},
    "initial": {"velocity"},
    "nodal_forces": {"vertices", "force"},
    "linear_constraints": {"terms", "offset", "stiffness", "name"},
    "discrete_springs": {
        "name",
        "pairs",
        "anchors",
        "stiffness",
        "tension_only",
        "force",
        "measure",
        "scale",
        "rest_length",
        "stiffness_scale",
    },
}

MESH_KEYS = {
    "generator": "rectangle, box or ellipsoid",
    "center": "ellipsoid: centre",
    "radii": "ellipsoid: semi-axes",
    "file": "path of a mesh file (relative to the scene file)",
    "surface": "path of a closed surface (STL, OBJ, PLY) to tetrahedralise (relative to the scene)",
    "size": "surface: target tetrahedron edge length in metres (default 0.05 of the box diagonal)",
    "mesher": "surface: auto, pytetwild, tetgen or gmsh (mesh_surface)",
    "target_elements": "surface: about this many tetrahedra (within 30 %) instead of a size",
    "epsilon": "surface, pytetwild: the envelope relative to the bounding-box diagonal",
    "envelope": "surface, pytetwild: the envelope in metres (default size / 20)",
    "coarsen": "surface, pytetwild: coarsen as far as the quality allows (true / false)",
    "smoothing": "surface: smooth a staircase before meshing: none, taubin or sinc",
    "smoothing_iterations": "surface: iterations of the smoothing filter (default 20)",
    "lower": "generator: lower corner",
    "upper": "generator: upper corner",
    "divisions": "generator: cells per axis",
    "pattern": "rectangle: triangle pattern; box: tetrahedral split (mirrored or uniform)",
    "grading": "box: per-axis grading exponents (1 uniform, p finer towards lower, -p upper)",
    "element": "box: tet (default), hex, hex20, hex27 or wedge; rectangle: triangle (default), "
    "quad, quad8 or quad9",
    "merge_coincident": "file: merge vertices that coincide (an unwelded seam) instead of refusing",
    "thickness": "shell: a solid shell of this thickness on the surface (with surface = ... or "
    "generator = 'shell')",
    "layers": "shell: cells through the thickness (default 1)",
    "reference": "shell: where the surface lies in the shell: middle (default), top or bottom",
    "points": "generator = 'shell': the surface's (n, 3) vertices",
    "faces": "generator = 'shell': its (k, 4) quadrilaterals or (k, 3) triangles",
}

#: the FEM body options a [simulation] table (short form) or a [[bodies]] table may set
FEM_BODY_OPTIONS = ("density", "mass", "order", "formulation")

#: the tables of one FEM body (top level in a one-body scene, inside each [[bodies]] entry)
FEM_BODY_KEYS = ("mesh", "material", "dirichlet", "traction", "body_force", "nodal_forces")

FEM_BODY_KEYS += ("initial", "pressure", "discrete_springs", "linear_constraints", "regions")

#: the keys of one of a body's [[bodies.regions]]
REGION_KEYS = ("name", "cells", "material", "formulation", "density")


def _regions(item: dict, mesh, source: str, label) -> dict:
    """[[bodies.regions]]: name, cells (one of the mesh file's cell sets), material = {...},
    formulation and density (default: the body's) -> ``add_body``'s regions."""
    from tissuesim.bodies.regions import Region
    from tissuesim.mesh.mesh import Mesh

    regions = {}
    for i, entry in enumerate(_table(item, "regions", source, array=True), start=1):
        where = label("regions", i)
        _unknown(entry, REGION_KEYS, where)
        for key in ("name", "cells", "material"):
            if key not in entry:
                raise SceneError(f"{where}: missing key {key!r}")
        cells = entry["cells"]
        if not isinstance(cells, str) or cells not in mesh.cell_sets:
            raise SceneError(
                f"{where}: cells must name one of the mesh's cell sets {sorted(mesh.cell_sets)}, "
                f"not {short(cells)}"
            )
        ids = np.asarray(mesh.cell_sets[cells])
        own = Mesh(mesh.points, mesh.cells[ids], source=mesh.source)  # directions per cell
        material = _material(entry, source, f"{where} material", own)
        if entry["name"] in regions:
            raise SceneError(f"{where}: region {entry['name']!r} is named twice")
        regions[entry["name"]] = Region(
            ids, material, entry.get("formulation"), entry.get("density")
        )
    return regions


def add_fem_body(
    sim, name: str, item: dict, base_dir: Path, source: str, label, options_where=None
) -> None:
    """A FEM body from its tables: mesh, material (required), density, mass, order,
    formulation, fix (a vertex selector), dirichlet, traction, body_force, nodal_forces (arrays
    of tables), initial."""
    if "mesh" not in item:
        raise SceneError(f"{label('mesh')}: missing: give a mesh = {{ generator = ... }} table")
    with _context(label("mesh")):
        mesh = _mesh(_table(item, "mesh", source), base_dir, label("mesh"))
    d = mesh.dim
    regions = None
    if "regions" in item:
        regions = _regions(item, mesh, source, label)
    material = None
    if regions is None or "material" in item:
        material = _material(item, source, label("material"), mesh)
    options = {k: item[k] for k in FEM_BODY_OPTIONS if k in item}
    with _context(options_where or label()):
        sim.add_body(name, mesh, material, regions=regions, **options)
    mesh = sim.body(name).mesh  # order = 2 adds midside nodes: select on the body's mesh
    if "fix" in item:
        vertices = _select(mesh, "vertices", item["fix"], label("fix"))
        with _context(label("fix")):
            sim.fix(name, vertices)
    for i, entry in enumerate(_table(item, "dirichlet", source, array=True), start=1):
        where = label("dirichlet", i)
        _unknown(entry, FEM_TABLE_KEYS["dirichlet"], where)
        if "vertices" not in entry:
            raise SceneError(f"{where}: missing key 'vertices' (a selector table)")
        vertices = _select(mesh, "vertices", entry["vertices"], where)
        disp = entry.get("displacement")
        g = None if disp is None else compile_vector(disp, d, f"{where} displacement")
        components = entry.get("components")
        if components is not None and not isinstance(components, list):
            raise SceneError(f"{where}: components must be a list of axes, e.g. [0]")
        with _context(where):
            sim.add_dirichlet(
                vertices, g, components, body=name, name=entry.get("name"),
                active=entry.get("active"),
            )  # fmt: skip
    for i, entry in enumerate(_table(item, "traction", source, array=True), start=1):
        where = label("traction", i)
        _unknown(entry, FEM_TABLE_KEYS["traction"], where)
        for key in ("facets", "traction"):
            if key not in entry:
                raise SceneError(f"{where}: missing key {key!r}")
        facets = _select(mesh, "facets", entry["facets"], where)
        with _context(where):
            sim.add_traction(facets, _field(entry["traction"], d, f"{where} traction"), body=name)
    for i, entry in enumerate(_table(item, "pressure", source, array=True), start=1):
        where = label("pressure", i)
        _unknown(entry, FEM_TABLE_KEYS["pressure"], where)
        for key in ("facets", "pressure"):
            if key not in entry:
                raise SceneError(f"{where}: missing key {key!r}")
        facets = _select(mesh, "facets", entry["facets"], where)
        value = of_time([entry["pressure"]], 1, f"{where} pressure", "a pressure")
        with _context(where):
            sim.add_follower_pressure(
                facets,
                lambda t, value=value: float(value(t)[0]),
                body=name,
                name=entry.get("name", "pressure"),
            )
    for i, entry in enumerate(_table(item, "body_force", source, array=True), start=1):
        where = label("body_force", i)
        _unknown(entry, FEM_TABLE_KEYS["body_force"], where)
        if "force_density" not in entry:
            raise SceneError(f"{where}: missing key 'force_density'")
        with _context(where):
            sim.add_body_force(
                _field(entry["force_density"], d, f"{where} force_density"), body=name
            )
    for i, entry in enumerate(_table(item, "nodal_forces", source, array=True), start=1):
        where = label("nodal_forces", i)
        _unknown(entry, FEM_TABLE_KEYS["nodal_forces"], where)
        for key in ("vertices", "force"):
            if key not in entry:
                raise SceneError(f"{where}: missing key {key!r}")
        vertices = _select(mesh, "vertices", entry["vertices"], where)
        force = of_time(entry["force"], d, f"{where} force", "a nodal force")
        with _context(where):
            sim.add_nodal_forces(vertices, force, body=name)
    springs = _table(item, "discrete_springs", source, array=True)
    if springs:
        from tissuesim.scene.tables.springs import add_spring_tables

        add_spring_tables(sim, name, springs, label)
    constraints = _table(item, "linear_constraints", source, array=True)
    if constraints:
        from tissuesim.scene.tables.springs import add_linear_constraint_tables

        add_linear_constraint_tables(sim, name, constraints, label)
    initial = _table(item, "initial", source)
    _unknown(initial, FEM_TABLE_KEYS["initial"], label("initial"))
    if "velocity" in initial:
        v = compile_vector(initial["velocity"], d, f"{label('initial')} velocity")
        with _context(label("initial")):
            sim.set_velocity(v(mesh.points, sim.time), body=name)


MESH_GENERATORS = {
    "rectangle": ("lower", "upper", "divisions", "pattern", "element"),
    "box": ("lower", "upper", "divisions", "grading", "pattern", "element"),
    "ellipsoid": ("center", "radii", "divisions"),
    "shell": ("points", "faces", "thickness", "layers", "reference"),
}
#: the keys of a solid shell of a surface file (mesh = { surface = "wall.stl", thickness = ... })
SHELL_OPTIONS = ("thickness", "layers", "reference")


def _mesh(table: dict, base_dir: Path, where: str):
    """A generated mesh (rectangle, box, ellipsoid) or a file (relative to the scene)."""
    from tissuesim.mesh import box, ellipsoid, read_mesh, rectangle

    if not isinstance(table, dict):
        raise SceneError(f"{where}: must be a table, e.g. mesh = {{ generator = 'box', ... }}")
    _unknown(table, MESH_KEYS, where)
    if "thickness" in table or table.get("generator") == "shell":
        return _shell_mesh(table, base_dir, where)
    if "surface" in table:
        return _surface_mesh(table, base_dir, where)
    surface_only = sorted(set(table) & set(SURFACE_OPTIONS))
    if surface_only:
        raise SceneError(
            f"{where}: {', '.join(surface_only)}: options of meshing a surface "
            "(surface = 'organ.stl') only"
        )
    if "file" in table:
        extra = set(table) - {"file", "merge_coincident"}
        if extra:
            raise SceneError(f"{where}: 'file' cannot be combined with {sorted(extra)}")
        if not isinstance(table["file"], str):
            raise SceneError(f"{where}: file must be a path (a string), not {short(table['file'])}")
        path = Path(table["file"])
        merge = table.get("merge_coincident", False)
        if not isinstance(merge, bool):
            raise SceneError(f"{where}: merge_coincident must be true or false, not {short(merge)}")
        return read_mesh(path if path.is_absolute() else base_dir / path, merge_coincident=merge)
    if "merge_coincident" in table:
        raise SceneError(
            f"{where}: merge_coincident applies to mesh files; generators never "
            "make coincident vertices"
        )
    generator = table.get("generator")
    if not isinstance(generator, str) or generator not in MESH_GENERATORS:
        close = difflib.get_close_matches(str(generator), list(MESH_GENERATORS), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise SceneError(
            f"{where}: give file = 'mesh.msh', surface = 'organ.stl' or generator = "
            f"'rectangle' | 'box' | 'ellipsoid' (got generator = {generator!r}){hint}"
        )
    kwargs = {k: v for k, v in table.items() if k != "generator"}
    for key in kwargs:
        if key not in MESH_GENERATORS[generator]:
            raise SceneError(
                f"{where}: {key!r} is not an argument of generator {generator!r}; it takes "
                f"{', '.join(MESH_GENERATORS[generator])}"
            )
    generators = {"rectangle": rectangle, "box": box, "ellipsoid": ellipsoid}
    return generators[generator](**kwargs)


def _shell_mesh(table: dict, base_dir: Path, where: str):
    """A solid shell (``solid_shell``): mesh = { surface = "wall.stl", thickness = 0.002 } or
    { generator = "shell", points = [...], faces = [...], thickness = 0.002 }, with layers and
    reference (default "middle": the surface is the wall's mid-surface)."""
    from tissuesim.mesh.generators.shells import read_shell_surface, solid_shell

    source = "surface" if "surface" in table else "generator"
    keys = {"surface"} if source == "surface" else {"generator", "points", "faces"}
    extra = sorted(set(table) - keys - set(SHELL_OPTIONS))
    if extra or "thickness" not in table:
        what = f"cannot be combined with {extra}" if extra else "needs a thickness"
        raise SceneError(
            f"{where}: a shell {what}; it takes surface = 'wall.stl' (or generator = 'shell', "
            f"points, faces) and {', '.join(SHELL_OPTIONS)}"
        )
    options = {k: table[k] for k in SHELL_OPTIONS if k in table}
    options.setdefault("reference", "middle")
    if isinstance(options.get("thickness"), bool) or not isinstance(
        options["thickness"], int | float
    ):
        raise SceneError(f"{where}: thickness must be a length in metres (a number > 0)")
    with _context(where):
        if source == "surface":
            path = table["surface"]
            if not isinstance(path, str):
                raise SceneError(f"{where}: surface must be a path (a string), not {short(path)}")
            full = Path(path) if Path(path).is_absolute() else base_dir / path
            points, faces = read_shell_surface(str(full))
        else:
            if "points" not in table or "faces" not in table:
                raise SceneError(f"{where}: generator = 'shell' needs points and faces")
            try:
                points = np.asarray(table["points"], dtype=np.float64)
                faces = np.asarray(table["faces"], dtype=np.int64)
            except (TypeError, ValueError):
                raise SceneError(
                    f"{where}: points must be [x, y, z] lists and faces lists of 3 or 4 "
                    "vertex indices (0-based)"
                ) from None
        return solid_shell(points, faces, **options)


#: the keys of mesh = { surface = ... } besides the path: tetrahedralize's keyword arguments
SURFACE_OPTIONS = (
    "size",
    "mesher",
    "target_elements",
    "epsilon",
    "envelope",
    "coarsen",
    "smoothing",
    "smoothing_iterations",
)


def _surface_mesh(table: dict, base_dir: Path, where: str):
    """mesh = { surface = "organ.stl", size = 0.004 }: mesh_surface (relative to the scene);
    the other keys of SURFACE_OPTIONS go to it by name (it checks them, naming the key)."""
    from tissuesim.mesh.from_surface.tetrahedralize import mesh_surface

    extra = set(table) - {"surface", *SURFACE_OPTIONS}
    if extra:
        raise SceneError(
            f"{where}: 'surface' cannot be combined with {sorted(extra)}; it takes "
            f"{', '.join(SURFACE_OPTIONS)}"
        )
    path = table["surface"]
    if not isinstance(path, str):
        raise SceneError(f"{where}: surface must be a path (a string), not {short(path)}")
    size = table.get("size")
    if size is not None and (isinstance(size, bool) or not isinstance(size, int | float)):
        raise SceneError(f"{where}: size must be a length in metres (a number), not {short(size)}")
    mesher = table.get("mesher", "auto")
    if not isinstance(mesher, str):
        raise SceneError(f"{where}: mesher must be a string such as 'auto', not {short(mesher)}")
    options = {k: table[k] for k in SURFACE_OPTIONS[2:] if k in table}
    full = Path(path) if Path(path).is_absolute() else base_dir / path
    with _context(where):
        return mesh_surface(full, size, mesher=mesher, **options)


def _select(mesh, kind: str, selector, where: str, key: str | None = None) -> np.ndarray:
    from tissuesim.mesh.queries import select

    if not isinstance(selector, dict) or len(selector) != 1:
        raise SceneError(
            f"{where}: {kind} must be a table with one selector out of "
            f"{sorted(SELECTORS[kind])}, e.g. {{ on_plane = {{ axis = 0, value = 0.0 }} }}"
        )
    ((how, args),) = selector.items()
    _unknown([how], SELECTORS[kind], f"{where} {kind}")
    prefix = "vertices" if kind == "vertices" else "facets"
    key = key or kind
    if how == "where":  # vertices (facets: all of whose vertices) where a condition holds
        inside = condition(args, f"{where} {key} where")(mesh.points)
        if kind == "vertices":
            ids = np.flatnonzero(inside)
        else:
            facets = select.all_boundary_facets(mesh)
            ids = facets[inside[facets].all(axis=1)]
        if len(ids) == 0:
            lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
            what = "vertex" if kind == "vertices" else "boundary facet"
            box = " x ".join(f"[{a:.6g}, {b:.6g}]" for a, b in zip(lo, hi, strict=True))
            raise SceneError(
                f"{where} {key}: where = {args!r} selects no {what}; its rest vertices span {box}"
            )
        return ids
    with _context(f"{where} {key} {how}"):
        if how == "tagged":
            return getattr(select, f"{prefix}_tagged")(mesh, args)
        if how == "boundary":
            if args is not True:
                raise SceneError(f"{where}: write {key} = {{ boundary = true }}")
            fn = select.boundary_vertices if kind == "vertices" else select.all_boundary_facets
            return fn(mesh)
        if not isinstance(args, dict):
            raise SceneError(f"{where}: {how} takes a table of arguments")
        fn = getattr(select, f"{prefix}_{how}")
        _unknown(args, list(inspect.signature(fn).parameters)[1:], f"{where} {key} {how}")
        return fn(mesh, **args)
