"""Read a FEBio 3.0 / 4.0 model (``.feb``) into plain data (``FebModel``): the parts
tissuesim can run, each checked where it is read. Whatever has no tissuesim counterpart is
refused with one line naming the XML element and its line; FEBio's solver tuning (which
changes how FEBio reaches the answer, not the answer) and its own output files are kept as
notes that ``run`` prints and ``convert`` writes into the scene."""

from __future__ import annotations

import gc
import math
import os

from tissuesim.febio.materials import MATERIAL_TYPES, UNCOUPLED, read_materials, read_mesh_data
from tissuesim.febio.model import FebModel, Node, _floats, _ints, _once, _unsupported
from tissuesim.febio.rigid.conditions import read_rigid
from tissuesim.febio.time_stepper import read_plot_level, read_time_stepper
from tissuesim.febio.xml import parse_feb

__all__ = ["read_feb", "MATERIAL_TYPES", "UNCOUPLED"]

#: Control children that tune FEBio's own solver or its output (notes)
CONTROL_NOTES = {
    "output_level", "plot_stride", "plot_range",
    "plot_zero_state", "output_stride", "adaptor_re_solve", "title", "optimize_bw",
}  # fmt: skip


def read_feb(path: str | os.PathLike[str], root: Node | None = None) -> FebModel:
    """Read a FEBio 3.0 or 4.0 model; FebError (one line, element and line) for anything
    tissuesim does not run. ``root``: the file's tree already parsed (``parse_feb``; an
    optimisation sets parameters in it, febio/optimize/)."""
    # the XML tree is millions of objects for a large model, and none in a reference cycle:
    # Python's cyclic collector, scanning them again and again while the sections are read,
    # took half of a 1e6-node read (35 s, 16 s without it)
    collecting = gc.isenabled()
    gc.disable()
    try:
        return _read(path, root)
    finally:
        if collecting:
            gc.enable()


def _read(path: str | os.PathLike[str], root: Node | None = None) -> FebModel:
    root = parse_feb(path) if root is None else root
    version = root.attrib.get("version", "")
    if version not in ("3.0", "4.0"):
        raise root.error(f"febio_spec version {version!r}: tissuesim reads versions 3.0 and 4.0")
    model = FebModel(source=os.fspath(path), version=version)
    for section in root.children:
        reader = SECTIONS.get(section.tag)
        if reader is None:
            raise _unsupported(section, "this section is not supported by tissuesim")
        reader(model, section)
    if not model.parts:
        raise root.error("no <Elements>: the model has no solid elements")
    for name, (_, _, _, node) in model.parts.items():
        if name not in model.domains:
            raise node.error(f"part {name!r} has no <SolidDomain> (no material)")
    loads = [d[2] for d in model.dirichlet if d[2] is not None]
    loads += [n[1] for n in model.nodal] + [t[2] for t in model.tractions] + model.body_loads
    loads += [c["offset"] for c in model.contacts if "offset" in c]
    loads += [f[2] for f in model.body_force_fields]
    for c in model.linear_constraints:  # febio/linear_constraints.py
        loads += [c["offset"], *(d[2] for d in c["terms"])]
    for load in loads:
        if load.curve is not None and load.curve not in model.curves:
            raise root.error(f"load curve {load.curve} is used but not defined in <LoadData>")
    take_rigid_walls(model)  # FEBio's rigid walls as tissuesim's (febio/constraint_sections.py)
    steppers = [p["time_stepper"] for p in model.phases] or [model.time_stepper]
    for stepper in steppers:
        number, node = (stepper or {}).get("curve", (None, None))
        if number is not None and number not in model.curves:
            raise node.error(f"load curve {number} is used but not defined in <LoadData>")
    _check_attributes(root, {id(n) for n in model.noted})
    return model


#: attributes that only label an element (FEBio refers to some by name; tissuesim reads the
#: names it needs), accepted where tissuesim does not read them
LABELS = {"name", "id"}


def _check_attributes(root: Node, skipped: set[int]) -> None:
    """Refuse the first attribute the reader never looked at (a misspelt ``lcc="1"`` would
    drop the load curve silently), except labels; elements kept as notes are not checked."""
    import difflib

    stack = [root]
    while stack:
        node = stack.pop()
        if id(node) in skipped:
            continue
        unread = [k for k in node.attrib.unread() if k not in LABELS]
        if unread:
            key = unread[0]
            known = [k for k in node.attrib.read if not dict.__contains__(node.attrib, k)]
            near = difflib.get_close_matches(key, known, n=1)
            hint = f" (did you mean {near[0]}?)" if near else ""
            raise node.error(
                f'attribute {key}="{node.attrib[key]}" is not one tissuesim reads on '
                f"<{node.tag}>{hint}: correct or remove it"
            )
        stack.extend(reversed(node.children))


def _step(model: FebModel, section: Node) -> None:
    """<Step>: its <step>s one after the other. A model of one step runs its conditions for
    the whole run; in a model of several, each step is a phase (its own Control: steps, step
    size, analysis) and the conditions and loads given in it hold during its time only
    (FEBio deactivates them at the step's end; its time runs on from the step before)."""
    steps = [c for c in section.children]
    for c in steps:
        if c.tag != "step":
            raise _unsupported(c, "expected <step>")
    model.steps = len(steps)
    start = 0.0
    for k, step in enumerate(steps):
        for child in step.children:
            if child.tag == "Control":
                _control(model, child)
        end = start + model.time_steps * model.step_size
        if len(steps) > 1:
            model.phases.append(
                {"time_steps": model.time_steps, "step_size": model.step_size,
                 "analysis": model.analysis, "newmark": model.newmark, "node": step,
                 "time_stepper": model.time_stepper, "plot_level": model.plot_level}
            )  # fmt: skip
            # the last step's conditions go on if the run is continued past its end
            model.window = (start, end if k < len(steps) - 1 else math.inf)
        for child in step.children:
            if child.tag == "Control":
                continue
            reader = STEP_SECTIONS.get(child.tag)
            if reader is None:
                raise _unsupported(child, "this step section is not supported by tissuesim")
            if child.tag == "Contact" and len(steps) > 1:
                raise child.error(
                    "contact given in one <step> of several: tissuesim's contact holds for the "
                    "whole run (give it in the model's <Contact> section)"
                )
            reader(model, child)
        start = end
    model.window = None


#: <solver> parameters of FEBio's time integrator (FESolidSolver2), FEBio's defaults
INTEGRATOR_PARAMETERS = {"rhoi": -2.0, "alpha": 1.0, "beta": 0.25, "gamma": 0.5}


def _solver(model: FebModel, node: Node) -> None:
    """<solver>: Newmark's beta and gamma (read as FEBio's FESolidSolver2 sets them up for
    a DYNAMIC step: rhoi = -2, its default, takes beta and gamma as given, rhoi = -1 the
    trapezoidal rule); everything else tunes FEBio's own Newton iterations (a note)."""
    kind = node.attrib.get("type", "solid")
    if kind != "solid":
        raise node.error(f"solver type {kind!r}: tissuesim runs FEBio's 'solid' solver")
    values = dict(INTEGRATOR_PARAMETERS)
    tuning = []
    seen: dict = {}
    for c in node.children:  # FEBio keeps the last of a tuning setting given twice
        if c.tag in INTEGRATOR_PARAMETERS and c.tag in seen:
            raise c.error(
                f"<{c.tag}> is given twice in <solver> (first at line {seen[c.tag].line}): keep one"
            )
        seen[c.tag] = c
    for c in node.children:
        if c.tag in INTEGRATOR_PARAMETERS:
            values[c.tag] = float(_floats(c, 1)[0])
            if c.tag in ("rhoi", "alpha"):
                model.integrator_nodes[c.tag] = c
        elif c.tag not in tuning:
            tuning.append(c.tag)
    rhoi, alpha = values["rhoi"], values["alpha"]
    if rhoi == -1.0:
        values["beta"], values["gamma"] = 0.25, 0.5
    model.newmark_parameters = (values["beta"], values["gamma"], rhoi, alpha, node)
    first = model.febio_solver is None
    if first:  # the first step's, for ``--febio-solver`` (FEBio's Quasin, solve/quasin.py)
        model.febio_solver = _quasin_settings(node)
    if tuning:
        if first:
            model.febio_solver_note = len(model.notes)
        model.note(node, f"FEBio's solver settings ({', '.join(tuning)}) not used: tissuesim's "
                   "Newton converges to its own tolerances")  # fmt: skip


#: <solver> settings of FEBio's Quasin (solve/quasin.py's FebioSettings) by their kind
QUASIN_FLOATS = ("dtol", "etol", "rtol", "min_residual", "max_residual", "lstol", "lsmin", "cmax")
QUASIN_INTS = ("lsiter", "max_ups", "max_refs")
QUASIN_FLAGS = ("diverge_reform", "reform_each_time_step", "reform_augment")
#: FEBio 2.5's <qnmethod> numbers
QN_NUMBERS = {"0": "BFGS", "1": "Broyden"}


def _quasin_settings(node: Node) -> dict:
    """FEBio's Quasin settings a <solver> gives (its <qn_method type=...> and children
    included, FEBio 2.5's flat <max_ups>, <cmax> and <qnmethod> too)."""
    out: dict = {}
    for c in node.children:
        if c.tag == "qn_method":
            kind = c.attrib.get("type") or (c.text or "").strip()
            out["qn_method"] = QN_NUMBERS.get(kind, kind)
            out.update(_quasin_settings(c))
        elif c.tag == "qnmethod":
            kind = (c.text or "").strip()
            out["qn_method"] = QN_NUMBERS.get(kind, kind)
        elif c.tag in QUASIN_FLOATS:
            out[c.tag] = float(_floats(c, 1)[0])
        elif c.tag in QUASIN_INTS:
            out[c.tag] = int(_ints(c)[0])
        elif c.tag in QUASIN_FLAGS:
            text = (c.text or "").strip().lower()
            if text not in ("0", "1", "true", "false"):
                raise c.error(f"<{c.tag}> must be 0 or 1, not {text[:20]!r}")
            out[c.tag] = text in ("1", "true")
    return out


def _newmark(model: FebModel) -> tuple[float, ...] | None:
    """A DYNAMIC step's scheme, checked, as FEBio's ``FESolidSolver2::Init`` sets it up:
    Newmark's (beta, gamma) (rhoi = -1: the trapezoidal rule; any other rhoi outside [0, 1]
    with alpha = 1: beta and gamma as given), or generalised-alpha's (alpha_f, alpha_m, beta,
    gamma) (0 <= rhoi <= 1: FEBio's weights from rhoi, its beta and gamma ignored; otherwise an
    alpha other than 1: alpha_f = alpha_m = alpha with beta and gamma as given)."""
    if model.analysis != "dynamic":
        return None
    beta, gamma, rhoi, alpha, node = model.newmark_parameters or (0.25, 0.5, -2.0, 1.0, None)
    from tissuesim.errors import InputError
    from tissuesim.time.integrators.generalized_alpha import check_generalized_alpha
    from tissuesim.time.integrators.newmark import check_newmark

    try:
        if 0.0 <= rhoi <= 1.0:
            return check_generalized_alpha(rhoi)
        if rhoi != -1.0 and alpha != 1.0:
            return check_generalized_alpha((alpha, alpha, beta, gamma))
        return check_newmark((beta, gamma))
    except InputError as exc:
        tag = "rhoi" if 0.0 <= rhoi <= 1.0 else "alpha" if rhoi != -1.0 and alpha != 1.0 else ""
        raise model.integrator_nodes.get(tag, node).error(str(exc)) from None


def _module(model: FebModel, node: Node) -> None:
    kind = node.attrib.get("type", node.text or "solid")
    if kind != "solid":
        raise node.error(f"module {kind!r}: tissuesim runs the 'solid' module only")


def _control(model: FebModel, node: Node) -> None:
    model.newmark_parameters = None  # FEBio makes each step's solver anew, with its defaults
    model.time_stepper = model.plot_level = None  # and its time stepper (fixed steps if none)
    _once(node)
    for child in node.children:
        tag = child.tag
        if tag == "analysis":
            kind = (child.attrib.get("type") or child.text).strip().lower()
            if kind not in ("static", "dynamic"):
                raise child.error(f"analysis {kind!r}: tissuesim runs STATIC and DYNAMIC")
            model.analysis = kind
        elif tag == "time_steps":
            steps = _ints(child)
            if len(steps) != 1 or steps[0] < 1:
                raise child.error(f"time_steps must be one integer >= 1, got {child.text[:40]!r}")
            model.time_steps = steps[0]
        elif tag == "step_size":
            model.step_size = float(_floats(child, 1)[0])
            if not model.step_size > 0:
                raise child.error("step_size must be > 0")
        elif tag == "solver":
            _solver(model, child)
        elif tag == "time_stepper":
            read_time_stepper(model, child)
        elif tag == "plot_level":
            read_plot_level(model, child)
        elif tag in CONTROL_NOTES:
            names = ", ".join(c.tag for c in child.children) or child.text
            model.note(child, f"FEBio's solver / output setting ({names}) not used: tissuesim "
                       "writes every step of its own output")  # fmt: skip
        else:
            raise _unsupported(child, "this Control setting is not supported by tissuesim")
    model.newmark = _newmark(model)
    if model.febio_solver is None:  # the first step gives no <solver>: FEBio's defaults
        model.febio_solver = {}


from tissuesim.febio.condition_sections import SECTIONS as _CONDITION_SECTIONS  # noqa: E402
from tissuesim.febio.constraint_sections import read_constraints, take_rigid_walls  # noqa: E402
from tissuesim.febio.discrete import read_discrete  # noqa: E402
from tissuesim.febio.initial import read_initial  # noqa: E402
from tissuesim.febio.mesh_sections import SECTIONS as _MESH_SECTIONS  # noqa: E402

STEP_SECTIONS = {
    "Control": _control,
    **{k: v for k, v in _CONDITION_SECTIONS.items() if k in ("Boundary", "Loads", "Contact")},
    "Rigid": read_rigid,
    "Constraints": read_constraints,
}
SECTIONS = {
    "Module": _module,
    "Step": _step,
    "Control": _control,
    "Material": read_materials,
    "MeshData": read_mesh_data,
    "Rigid": read_rigid,
    "Constraints": read_constraints,
    "Discrete": read_discrete,
    "Initial": read_initial,
    **_MESH_SECTIONS,
    **_CONDITION_SECTIONS,
}
