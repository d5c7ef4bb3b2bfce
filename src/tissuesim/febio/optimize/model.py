"""The model an optimisation runs (FEBio's ``-i`` file), built for any parameter values: each
<param> names an element of the model (``fem.material[0].c3``, ``fem.material('Skin').E``,
``fem.material('Mix').solid.E``, a point of a material's curve ``fem.material('tissue').
relaxation.tau1.points[1].y``) whose text is set before the model is read, as FEBio sets the
parameter; the quantities the objective reads become log requests of the model, so the
converter maps FEBio's node and element ids to the scene's bodies and rows."""

from __future__ import annotations

import re
import tempfile
import warnings
from pathlib import Path

import numpy as np

from tissuesim.errors import InputError
from tissuesim.febio.optimize.task import OptimizeTask, Quantity
from tissuesim.febio.xml import Node, parse_feb

__all__ = ["ModelBuilder"]

_MATERIAL = re.compile(
    r"fem\.material(?:\[(\d+)\]|\(\s*'([^']*)'\s*\))((?:\.\w+)+?)(?:\.points\[(\d+)\]\.([xy]))?$"
)
_VARIABLE = re.compile(r"fem\.(\w+)$")  # a global parameter, <Globals><Variables><var name>
#: the file name of the log request behind the objective's k-th quantity
_FILE = "optimize_quantity_{}.csv"


class ModelBuilder:
    """``simulation(values)``: the model as a Simulation with its parameters set to
    ``values`` (FEBio's names -> numbers); ``observations``: the objective's quantities as
    ``identification`` observations of those simulations."""

    def __init__(self, model_path: str | Path, task: OptimizeTask,
                 febio_solver: bool = False) -> None:  # fmt: skip
        from tissuesim.febio.reader import read_feb

        self.febio_solver = febio_solver
        self.path = Path(model_path)
        self.root = parse_feb(self.path)
        # FEBio's name -> (the element it sets, which of a curve point's two numbers or None)
        self.targets = {p.name: _element(self.root, p.name, p.node) for p in task.parameters}
        self.quantities = _quantities(task)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            model = read_feb(self.path, root=self.root)  # refusals name the model's lines
        notes = list(model.notes)
        if febio_solver and model.febio_solver_note is not None:
            del notes[model.febio_solver_note]  # the <solver> settings are used then
        self.notes = [str(w.message) for w in caught] + [f"not used: {n}" for n in notes]
        for note in dict.fromkeys(self.notes):  # as a run of the model says them, once
            warnings.warn(note, UserWarning, stacklevel=2)
        self._dir = tempfile.TemporaryDirectory(prefix="tissuesim-optimize-")
        self.observations = None
        self.simulation({})  # the model as given: refusals now, the observations mapped

    def close(self) -> None:
        self._dir.cleanup()

    def simulation(self, values: dict):
        """A fresh Simulation of the model with ``values`` set (the others as in the file)."""
        from tissuesim.febio.reader import read_feb
        from tissuesim.febio.scene import febio_scene
        from tissuesim.mesh import write_mesh
        from tissuesim.scene.loader import build_scene

        kept = []
        for name, value in values.items():
            node, component = self.targets[name]
            kept.append((node, node.text))
            if component is None:
                node.text = repr(float(value))
            else:  # one number of a curve's point "x,y"
                xy = [float(v) for v in node.text.split(",")]
                xy[component] = float(value)
                node.text = ",".join(repr(v) for v in xy)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model = read_feb(self.path, root=self.root)
                _log_requests(model, self.quantities, self.targets)
                data, meshes = febio_scene(model, self.path.stem)
                if self.febio_solver:  # FEBio's steps and stopping points (febio/convert.py)
                    from tissuesim.febio.convert import _use_febio_solver

                    _use_febio_solver(model, data)
        finally:
            for node, text in reversed(kept):
                node.text = text
        base = Path(self._dir.name)
        for file, mesh in meshes.items():
            if not (base / file).exists():  # the same mesh for every value: written once
                write_mesh(mesh, base / file, file_format="gmsh22")
        if self.observations is None:
            self.observations = _observations(self.quantities, data)
        # the objective's requests are read from the state, not written
        data["logfiles"] = [t for t in data.get("logfiles", [])
                            if not t["file"].startswith("optimize_quantity_")]  # fmt: skip
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = build_scene(data, base_dir=base, source=str(self.path), name=self.path.stem)
        return scene.simulation, scene


def _element(root: Node, name: str, where: Node) -> tuple[Node, int | None]:
    """The model's element a <param name> sets, and for a curve's point which of its numbers
    (0: x, 1: y; None: the element's one number)."""
    m = _MATERIAL.match(name.strip())
    variable = _VARIABLE.match(name.strip())
    if m is None and variable is not None:  # a global parameter: <Globals><Variables><var>
        section = root.find("Globals")
        holder = None if section is None else section.find("Variables")
        found = [] if holder is None else [
            v for v in holder.children if v.tag == "var" and v.attrib.get("name") == variable[1]
        ]  # fmt: skip
        if not found:
            raise where.error(f"{name!r}: the model has no <var name={variable[1]!r}> in "
                              "<Globals><Variables>")  # fmt: skip
        node = found[0]
    elif m is None and re.search(r"\.points\[\d+\]\.[xy]$", name.strip()):
        raise where.error(
            f"{name!r}: tissuesim optimises the points of a material's curves (fem.material"
            "('name').relaxation.tau1.points[1].y), not of load curves"
        )
    elif m is None:
        raise where.error(
            f"{name!r}: tissuesim optimises material parameters, named fem.material[i].name or "
            "fem.material('material').name, and global parameters fem.name (<Globals> "
            "<Variables>)"
        )
    else:
        node = _material_element(root, name, m, where)
    component = None
    if m is not None and m[4] is not None:  # a curve's point: <points><point>x,y</point>
        points = [c for c in node.children if c.tag in ("point", "pt")]
        if node.tag != "points" or not points:
            raise where.error(f"{name!r}: the model's <{node.tag}> (line {node.line}) holds no "
                              "<point>s")  # fmt: skip
        i = int(m[4])
        if i >= len(points):
            raise where.error(f"{name!r}: the curve at line {node.line} has {len(points)} "
                              f"points (0 to {len(points) - 1})")  # fmt: skip
        node, component = points[i], "xy".index(m[5])
    try:
        numbers = [float(v) for v in node.text.split(",")]
    except ValueError:
        numbers = []
    if len(numbers) != (1 if component is None else 2):
        raise where.error(f"{name!r}: the model's <{node.tag}> (line {node.line}) is not "
                          f"{'a number' if component is None else 'a point x,y'} "
                          f"({node.text!r})")  # fmt: skip
    return node, component


def _material_element(root: Node, name: str, m: re.Match, where: Node) -> Node:
    """The element of a material parameter fem.material[i].a.b or fem.material('x').a.b."""
    section = root.find("Material")
    materials = [] if section is None else [c for c in section.children if c.tag == "material"]
    if m[1] is not None:
        i = int(m[1])
        if i >= len(materials):
            raise where.error(f"{name!r}: the model has {len(materials)} materials")
        node = materials[i]
    else:
        found = [c for c in materials if c.attrib.get("name") == m[2]]
        if not found:
            names = [c.attrib.get("name") for c in materials]
            raise where.error(f"{name!r}: no material named {m[2]!r} in the model ({names})")
        node = found[0]
    parts = m[3].strip(".").split(".") + (["points"] if m[4] is not None else [])
    for part in parts:
        child = node.find(part)
        if child is None:
            raise where.error(
                f"{name!r}: <{node.tag}> at line {node.line} of the model has no <{part}> "
                "(give the parameter in the model to optimise it)"
            )
        node = child
    return node


def _quantities(task: OptimizeTask) -> list[Quantity]:
    if task.objective == "data-fit":
        q, x = task.series
        return [q] if x is None else [q, x]
    return [q for q, _ in task.targets]


def _log_requests(model, quantities: list[Quantity], targets: dict) -> None:
    """Each node and element quantity as a log request of the model (febio/logfiles.py)."""
    for k, q in enumerate(quantities):
        if q.kind == "node":
            if q.by_index:
                if not 0 <= q.item < len(model.nodes):
                    raise InputError(f"{q.text}: the model has {len(model.nodes)} nodes")
                rows = np.array([q.item])
            elif q.item not in model._node_index:
                raise InputError(f"{q.text}: no node with id {q.item} in the model")
            else:
                rows = np.array([model._node_index[q.item]])
            model.logfiles.append({"kind": "node_data", "data": ["x"], "items": rows,
                                   "file": _FILE.format(k), "node": None})  # fmt: skip
        elif q.kind in ("element", "filter"):
            if q.kind == "element":
                if q.item not in model._element_index:
                    raise InputError(f"{q.text}: no element with id {q.item} in the model")
                items = [model._element_index[q.item]]
            elif q.item in model.element_sets:
                items = list(model.element_sets[q.item][0])
            elif q.item in model.parts:
                items = [(q.item, r) for r in range(len(model.parts[q.item][1]))]
            else:
                raise InputError(f"{q.text}: no element set or part {q.item!r} in the model")
            model.logfiles.append({"kind": "element_data", "data": ["J"], "items": items,
                                   "file": _FILE.format(k), "node": None})  # fmt: skip


def _observations(quantities: list[Quantity], data: dict) -> list:
    from tissuesim.identification.observations import (
        ElementData,
        EnclosedVolume,
        NodeData,
        RigidForce,
    )

    tables = {t["file"]: t for t in data.get("logfiles", [])}
    out = []
    for k, q in enumerate(quantities):
        if q.kind == "rigid":  # the converter names a rigid body after its material
            out.append(RigidForce(q.item, q.variable))
            continue
        if q.kind == "surface":
            out.append(EnclosedVolume(q.item))  # on the body whose mesh has the surface
            continue
        mine = [t for f, t in tables.items() if f.startswith(_FILE.format(k)[:-4])]
        if len(mine) != 1:
            raise InputError(f"{q.text}: its items are not on one deformable body")
        t = mine[0]
        body = t.get("body")
        if q.kind == "node":
            out.append(NodeData(q.variable, t["nodes"] if "nodes" in t else [0], body))
        else:
            cells = t.get("elements")
            out.append(ElementData(q.variable, cells, body,
                                   reduce=q.reduce))  # fmt: skip
    return out
