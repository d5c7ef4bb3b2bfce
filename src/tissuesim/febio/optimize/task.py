"""A FEBio optimisation file (``<febio_optimize version="2.0">``, FEBio's ``-s`` file) read into
what tissuesim runs: the method and its settings, the parameters (name, start, bounds, scale)
and the objective (data-fit, target, node-data or element-data), as FEBio's
``FEOptimizeInput`` reads them. Anything else is refused in one line naming the element."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field

import numpy as np

from tissuesim.febio.xml import Node, parse_feb

__all__ = ["OptimizeTask", "Parameter", "Quantity", "read_optimize", "quantity"]

METHODS = ("levmar", "constrained levmar")
#: <Options> settings tissuesim uses (FEBio's names) and those it reads and does not need
SETTINGS = {"obj_tol": float, "f_diff_scale": float, "max_iter": int, "tau": float}
IGNORED = ("log_level", "print_level", "scale_parameters")


@dataclass(frozen=True)
class Parameter:
    """One <param>: FEBio's name, its start, bounds and scale factor (FEBio's 4th value)."""

    name: str
    initial: float
    low: float
    high: float
    scale: float
    node: Node = field(repr=False, compare=False)


@dataclass(frozen=True)
class Quantity:
    """What the model reports, by FEBio's name: ``kind`` "element" (element_data variable or
    ``=``-expression of element ``item``: an id), "node" (node_data variable of node ``item``:
    an id, or a 0-based index with ``by_index``), "surface" (surface_data ``volume`` of the
    surface ``item``), "filter" (``reduce`` "sum" / "mean" of an element expression over the
    element set ``item``) or "rigid" (a rigid body's force or moment)."""

    kind: str
    variable: str
    item: int | str
    text: str
    by_index: bool = False
    reduce: str | None = None


@dataclass
class OptimizeTask:
    """A whole <febio_optimize> file."""

    source: str
    method: str = "levmar"
    obj_tol: float = 0.001
    f_diff_scale: float = 0.001
    max_iter: int = 100
    tau: float = 1e-3
    parameters: list[Parameter] = field(default_factory=list)
    #: "data-fit": ``series`` (Quantity, ordinate Quantity or None: time) and ``data`` (k, 2);
    #: "target" / "node-data" / "element-data": ``targets`` [(Quantity, value)] at the end
    objective: str = ""
    series: tuple | None = None
    data: np.ndarray | None = None
    targets: list = field(default_factory=list)
    node: Node | None = field(default=None, repr=False)


_ELEMENT = re.compile(r"fem\.element_data\(\s*'([^']*)'\s*,\s*(\d+)\s*\)$")
_NODE_DATA = re.compile(r"fem\.node_data\(\s*'([^']*)'\s*,\s*(\d+)\s*\)$")
_SURFACE = re.compile(r"fem\.surface_data\(\s*'([^']*)'\s*,\s*'([^']*)'\s*\)$")
_NODE_POSITION = re.compile(r"fem\.mesh\.node(?:\[(\d+)\]|\.fromId\((\d+)\))\.position\.([xyz])$")
_RIGID = re.compile(r"fem\.rigidbody\(\s*'([^']*)'\s*\)\.([FM][xyz])$")


def quantity(text: str, node: Node) -> Quantity:
    """A FEBio quantity name (``fem.element_data('sx', 1)``, ``fem.mesh.node[10].position.z``,
    ``fem.mesh.node.fromId(22).position.z``, ``fem.node_data('ux', 3)``,
    ``fem.surface_data('volume', 'Surface1')``, ``fem.rigidbody('name').Fz``)."""
    text = (text or "").strip()
    if m := _ELEMENT.match(text):
        return Quantity("element", m[1], int(m[2]), text)
    if m := _NODE_DATA.match(text):
        return Quantity("node", m[1], int(m[2]), text)
    if m := _NODE_POSITION.match(text):
        if m[1] is not None:
            return Quantity("node", m[3], int(m[1]), text, by_index=True)
        return Quantity("node", m[3], int(m[2]), text)
    if m := _SURFACE.match(text):
        if m[1] != "volume":
            raise node.error(f"{text!r}: tissuesim reports a surface's 'volume' only")
        return Quantity("surface", "volume", m[2], text)
    if m := _RIGID.match(text):
        return Quantity("rigid", m[2], m[1], text)
    raise node.error(
        f"{text!r} is not a quantity tissuesim reports for an optimisation (fem.element_data"
        "('sx', id), fem.node_data('ux', id), fem.mesh.node[i].position.z, fem.mesh.node."
        "fromId(id).position.z, fem.surface_data('volume', 'surface'), fem.rigidbody('name')."
        "Fz)"
    )


def read_optimize(path: str | os.PathLike[str]) -> OptimizeTask:
    """Read an optimisation file; FebError (one line, element and line) for what is not run."""
    root = parse_feb(path, root_tag="febio_optimize")
    if root.attrib.get("version") != "2.0":
        raise root.error(f"version {root.attrib.get('version')!r}: FEBio reads version 2.0")
    task = OptimizeTask(source=os.fspath(path))
    for section in root.children:
        if section.tag == "Options":
            _options(task, section)
        elif section.tag == "Parameters":
            _parameters(task, section)
        elif section.tag == "Objective":
            _objective(task, section)
        elif section.tag == "Constraints":
            raise section.error("linear constraints between parameters are not supported by "
                                "tissuesim (remove them to run: the bounds are kept)")  # fmt: skip
        else:
            raise section.error("not an element of an optimisation file (Options, Parameters, "
                                "Objective)")  # fmt: skip
    if not task.parameters:
        raise root.error("no <Parameters><param>: nothing to optimise")
    if not task.objective:
        raise root.error("no <Objective>")
    return task


def _numbers(node: Node, count: tuple[int, ...]) -> list[float]:
    try:
        values = [float(v) for v in node.text.replace(",", " ").split()]
    except ValueError:
        raise node.error(f"expected numbers, got {node.text!r}") from None
    if len(values) not in count or not all(np.isfinite(values)):
        raise node.error(f"expected {' or '.join(map(str, count))} numbers, got {node.text!r}")
    return values


def _options(task: OptimizeTask, node: Node) -> None:
    kind = node.attrib.get("type", "levmar")
    if kind not in METHODS:
        methods = " and ".join(METHODS)
        raise node.error(f'type="{kind}": tissuesim runs {methods} (FEBio\'s Levenberg-'
                         "Marquardt, with gradients from the run's sensitivities)")  # fmt: skip
    task.method = kind
    for c in node.children:
        if c.tag in IGNORED:
            continue
        if c.tag not in SETTINGS:
            raise c.error(f"not an option tissuesim reads ({', '.join(SETTINGS)})")
        value = _numbers(c, (1,))[0]
        if value <= 0 or (SETTINGS[c.tag] is int and value != int(value)):
            raise c.error(f"{c.tag} must be a positive {SETTINGS[c.tag].__name__}")
        setattr(task, c.tag, SETTINGS[c.tag](value))


def _parameters(task: OptimizeTask, node: Node) -> None:
    for c in node.children:
        if c.tag != "param":
            raise c.error("expected <param name=...>start, min, max[, scale]</param>")
        name = c.attrib.get("name")
        if not name:
            raise c.error('a <param> needs name="fem.material(...).parameter"')
        v = _numbers(c, (3, 4))
        start, low, high, scale = (*v, 1.0) if len(v) == 3 else v
        if not low <= start <= high:
            raise c.error(f"start {start:g} is not within its bounds [{low:g}, {high:g}]")
        task.parameters.append(Parameter(name, start, low, high, scale, c))


def _objective(task: OptimizeTask, node: Node) -> None:
    kind = node.attrib.get("type")
    task.objective, task.node = kind, node
    if kind == "data-fit":
        _data_fit(task, node)
    elif kind == "target":
        for c in node.children:
            if c.tag != "var":
                raise c.error('a target objective takes <var name="...">target</var>')
            task.targets.append((quantity(c.attrib.get("name"), c), _numbers(c, (1,))[0]))
    elif kind in ("node-data", "element-data"):
        _table(task, node, kind)
    else:
        raise node.error(f'type="{kind}": tissuesim runs data-fit, target, node-data and '
                         "element-data objectives")  # fmt: skip
    if kind != "data-fit" and not task.targets:
        raise node.error("the objective has no data")


def _data_fit(task: OptimizeTask, node: Node) -> None:
    for c in node.children:
        if c.tag == "fnc":
            task.series = _source(c)
        elif c.tag == "data":
            if c.attrib.get("import") is not None:
                raise c.error('data import="..." is not supported by tissuesim: give the '
                              "points in the file")  # fmt: skip
            task.data = np.array([_numbers(p, (2,)) for p in c.children])
        else:
            raise c.error("a data-fit objective takes <fnc> and <data>")
    if task.series is None or task.data is None or not len(task.data):
        raise node.error("a data-fit objective needs <fnc> and <data> with points")


def _source(node: Node) -> tuple:
    kind = node.attrib.get("type")
    if kind == "parameter":
        param = node.find("param")
        if param is None:
            raise node.error('<fnc type="parameter"> needs <param name="..."/>')
        ordinate = node.find("ordinate")
        x = None if ordinate is None else quantity(ordinate.attrib.get("name"), ordinate)
        return quantity(param.attrib.get("name"), param), x
    if kind in ("filter_sum", "filter_avg"):
        data = node.find("element_data")
        if data is None or len(node.children) != 1:
            raise node.error(f'<fnc type="{kind}"> takes one <element_data data=... '
                             "elem_set=.../> (node data sums are not supported)")  # fmt: skip
        expression, elements = data.attrib.get("data"), data.attrib.get("elem_set")
        if not expression or not elements:
            raise data.error('needs data="..." and elem_set="..."')
        reduce = "sum" if kind == "filter_sum" else "mean"
        return Quantity("filter", expression.lstrip("="), elements, expression, reduce=reduce), None
    raise node.error(f'<fnc type="{kind}">: tissuesim takes parameter, filter_sum and '
                     "filter_avg")  # fmt: skip


def _table(task: OptimizeTask, node: Node, kind: str) -> None:
    var = node.find("var")
    data = node.find("data")
    if var is None or data is None:
        raise node.error(f"a {kind} objective needs <var type=...> and <data>")
    names = [v.strip() for v in (var.attrib.get("type") or "").split(";") if v.strip()]
    if not names:
        raise var.error('needs type="..." (a variable, or several separated by ";")')
    item = "node" if kind == "node-data" else "elem"
    for c in data.children:
        if c.tag != item or c.attrib.get("id") is None:
            raise c.error(f'expected <{item} id="...">values</{item}>')
        values = _numbers(c, (len(names),))
        ident = int(c.attrib["id"])
        for name, value in zip(names, values, strict=True):
            q = Quantity("node" if item == "node" else "element", name, ident, f"{item} {ident}")
            task.targets.append((q, value))
