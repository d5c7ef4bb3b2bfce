"""The plain data a FEBio model is read into (``FebModel``) and the helpers every section
reader shares (numbers, integers and flags from element text, refusals)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tissuesim.febio.xml import FebError, Node

__all__ = ["Curve", "Load", "FebModel"]


@dataclass
class Curve:
    """A FEBio load curve: points (t, y), interpolate and extend as FEBio names them."""

    points: np.ndarray
    interpolate: str = "LINEAR"
    extend: str = "CONSTANT"


@dataclass
class Load:
    """A scaled, possibly curve-driven quantity: value * curve(t) (curve None: constant),
    applied during the time window (t0, t1] of the <step> it is given in (None: always)."""

    value: np.ndarray
    curve: int | None = None
    window: tuple[float, float] | None = None


@dataclass
class FebModel:
    """What a FEBio model says, in tissuesim's terms (0-based node indices)."""

    source: str
    version: str
    analysis: str = "static"
    time_steps: int = 10
    step_size: float = 0.1
    nodes: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    #: name -> (cell type, (k, nv) node indices, FEBio element ids)
    parts: dict = field(default_factory=dict)
    #: material name -> (model, parameters, density, FEBio type, Orientation or None)
    materials: dict = field(default_factory=dict)
    #: part name -> (material name, formulation or None)
    domains: dict = field(default_factory=dict)
    node_sets: dict = field(default_factory=dict)
    #: name -> ((k, 3|4) corner nodes of each facet, its Node); a quadratic facet's corners
    surfaces: dict = field(default_factory=dict)
    #: <Globals><Variables>: name -> value (``fem.name`` in a math expression)
    variables: dict = field(default_factory=dict)
    #: name -> every node of the surface's facets, a quadratic facet's mid-side ones included
    #: (what "@surface:name" holds in a condition, as in FEBio)
    surface_nodes: dict = field(default_factory=dict)
    element_sets: dict = field(default_factory=dict)
    surface_pairs: dict = field(default_factory=dict)
    #: (node set, components or None for all, Load or None for clamped, name, window)
    dirichlet: list = field(default_factory=list)
    nodal: list = field(default_factory=list)  # (node set, Load (3,))
    tractions: list = field(default_factory=list)  # (surface, "pressure"|"traction", Load)
    body_loads: list = field(default_factory=list)  # Load (3,): force per unit mass applied
    #: FEBio 3's non-const body loads: (component, expression of x, y, z, t, Load of its
    #: curve), the force per unit mass applied (condition_sections.py)
    body_force_fields: list = field(default_factory=list)
    contacts: list = field(default_factory=list)  # dicts: type, surfaces, friction, wall...
    curves: dict = field(default_factory=dict)
    #: "mat_axis" / "fiber" -> {(part, row): (value, XML element)} from <MeshData>
    element_data: dict = field(default_factory=dict)
    #: named <ElementData name=...> maps (a material parameter given as type="map"): name ->
    #: (XML element, {(part, row): value}) (febio/materials/axes.py)
    element_maps: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)  # "file:line <tag>: what is not used"
    #: <logfile> requests (febio/logfiles.py): kind, data, node rows or (part, row) cells
    #: (None: all), file, node
    logfiles: list = field(default_factory=list)
    #: rigid body material name -> {"held": {dof: Load or None}, "force" / "moment": [(axis,
    #: Load)]} (febio/rigid/conditions.py); node sets that move with a rigid body: (set,
    #: body, element)
    rigid: dict = field(default_factory=dict)
    rigid_nodes: list = field(default_factory=list)
    #: rigid connectors (febio/rigid/connectors.py): dicts of a [[rigid_joints]] table with
    #: Loads for prescribed values and material names for the bodies
    rigid_connectors: list = field(default_factory=list)
    #: "file:line <tag>: what the converter changed" (contact surfaces set apart)
    changes: list = field(default_factory=list)
    #: <DiscreteSet> name -> ((k, 2) node rows, element); <Discrete> springs: dicts of a set,
    #: its law and parameters (febio/discrete.py)
    discrete_sets: dict = field(default_factory=dict)
    #: <bc type="linear constraint">: dicts of parent (row, axis), children (row, axis, Load),
    #: offset Load (febio/linear_constraints.py)
    linear_constraints: list = field(default_factory=list)
    #: <Initial> velocities: (node set, (3,) velocity, element) (febio/initial.py)
    initial_velocity: list = field(default_factory=list)
    springs: list = field(default_factory=list)
    #: rigid walls (febio/constraint_sections.py): name, surface, unit plane, penalty, offset
    #: Load, augmented, tolerance; taken from ``contacts`` once the model is read
    rigid_walls: list = field(default_factory=list)
    steps: int = 1
    #: a DYNAMIC analysis' Newmark (beta, gamma); the <solver> values read and their elements
    newmark: tuple[float, float] | None = None
    newmark_parameters: tuple | None = None
    integrator_nodes: dict = field(default_factory=dict)
    #: the first step's <solver> settings of FEBio's Quasin (solve/quasin.py's FebioSettings
    #: keys; {} where it gives none) and the index of its "not used" note in ``notes``
    febio_solver: dict | None = None
    febio_solver_note: int | None = None
    #: one dict per <step> of a model of several (time_steps, step_size, analysis)
    phases: list = field(default_factory=list)
    #: the <time_stepper> of the Control being read (febio/time_stepper.py), its plot_level
    time_stepper: dict | None = None
    plot_level: str | None = None
    #: the time window (t0, t1] of the <step> being read (None: the whole run)
    window: tuple[float, float] | None = None
    #: elements kept as notes: their attributes and children are not read (not refused)
    noted: list = field(default_factory=list, repr=False)
    _node_index: dict = field(default_factory=dict, repr=False)  # FEBio node id -> row
    _element_index: dict = field(default_factory=dict, repr=False)  # id -> (part, row)

    def note(self, node: Node, text: str) -> None:
        """Keep a note about an accepted element that tissuesim does not use."""
        self.notes.append(f"{node.where()}: {text}")
        self.noted.append(node)


def _floats(node: Node, count: int | None = None) -> np.ndarray:
    try:
        values = np.array([float(v) for v in node.text.replace(";", ",").split(",")])
    except ValueError:
        raise node.error(f"expected numbers separated by commas, got {node.text[:60]!r}") from None
    if count is not None and values.size != count:
        raise node.error(f"expected {count} numbers, got {values.size}")
    if not np.all(np.isfinite(values)):
        raise node.error("values must be finite")
    return values


def _ints(node: Node, text: str | None = None) -> list[int]:
    try:
        return [int(v) for v in (node.text if text is None else text).split(",") if v.strip()]
    except ValueError:
        raise node.error(f"expected integers separated by commas, got {node.text[:60]!r}") from None


def _int_attr(node: Node, key: str, what: str) -> int | None:
    """The integer attribute ``key`` (None if absent); a FebError naming the element, its line
    and the attribute for one that is not an integer (``lc="one"``, ``id="five"``)."""
    text = node.attrib.get(key)
    if text is None:
        return None
    try:
        return int(text)
    except ValueError:
        raise node.error(f'{key}="{text}": {what} must be an integer') from None


def _once(node: Node) -> dict[str, Node]:
    """``node``'s children by tag, each given once: a parameter given twice (FEBio would
    keep one of them) is refused with its line."""
    found: dict[str, Node] = {}
    for c in node.children:
        if c.tag in found:
            raise c.error(
                f"<{c.tag}> is given twice in <{node.tag}> (first at line {found[c.tag].line}): "
                "keep one"
            )
        found[c.tag] = c
    return found


def _flag(node: Node) -> bool:
    text = node.text.strip().lower()
    if text not in ("0", "1", "true", "false"):
        raise node.error(f"expected 0 or 1, got {node.text!r}")
    return text in ("1", "true")


def _unsupported(node: Node, what: str = "is not supported by tissuesim") -> FebError:
    return node.error(f"{what} (see docs/guide/febio.md for what is)")


def _load(model: FebModel, node: Node, count: int) -> Load:
    """value * curve: the element's numbers and its lc attribute."""
    curve = _int_attr(node, "lc", "a load curve id (a <load_controller>'s id)")
    return Load(_floats(node, count), curve, model.window)


def _children(node: Node, allowed: set[str]) -> dict[str, Node]:
    for c in node.children:
        if c.tag not in allowed:
            raise _unsupported(c, f"this parameter of <{node.tag}> is not supported by tissuesim")
    return _once(node)


def _index(model: FebModel, node: Node, ids: list[int]) -> np.ndarray:
    """FEBio node ids -> 0-based rows of model.nodes."""
    lookup = model._node_index
    try:
        return np.array([lookup[i] for i in ids], dtype=np.int64)
    except KeyError as exc:
        raise node.error(f"node id {exc.args[0]} is not defined in <Nodes>") from None
