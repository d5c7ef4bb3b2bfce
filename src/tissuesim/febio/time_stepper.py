"""FEBio's ``<time_stepper>`` and ``plot_level`` (in ``<Control>``): read into the model and
written into the scene as tissuesim's adaptive steps (``time/adaptive.py``), one phase per
FEBio step, so that a model steps as FEBio steps it (FEBio's rule in
``FECore/FETimeStepController.cpp``)."""

from __future__ import annotations

import math

from tissuesim.febio.model import FebModel, _flag, _floats, _int_attr, _ints, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["read_time_stepper", "read_plot_level", "adaptive_table", "run_steps"]

#: <time_stepper> parameters (FEBio's FETimeStepController), read as numbers
NUMBERS = ("dtmin", "dtmax", "cutback")
INTEGERS = ("max_retries", "opt_iter", "aggressiveness")
#: plot levels tissuesim writes as FEBio does
PLOT_LEVELS = {"PLOT_MAJOR_ITRS": "steps", "PLOT_MUST_POINTS": "must_points"}


def read_time_stepper(model: FebModel, node: Node) -> None:
    """``<time_stepper>``: dtmin, dtmax (a must-point curve with ``lc``), max_retries,
    opt_iter, aggressiveness, cutback, dtforce; anything else is refused with its line."""
    kind = node.attrib.get("type", "default")
    if kind != "default":
        raise node.error(f"time_stepper type {kind!r}: tissuesim runs FEBio's 'default' one")
    settings: dict = {"node": node}
    for tag, c in _once(node).items():
        if tag == "dtmax":
            curve = _int_attr(c, "lc", "a load curve id (a <load_controller>'s id)")
            if curve is not None:
                settings["curve"] = (curve, c)
                if not c.text.strip():
                    continue
        if tag in NUMBERS:
            settings[tag] = float(_floats(c, 1)[0])
        elif tag in INTEGERS:
            values = _ints(c)
            if len(values) != 1 or values[0] < 0:
                raise c.error(f"{tag} must be one integer >= 0, got {c.text[:40]!r}")
            settings[tag] = values[0]
        elif tag == "dtforce":
            settings[tag] = _flag(c)
        else:
            raise _unsupported(c, "this time_stepper setting is not supported by tissuesim")
    model.time_stepper = settings


def read_plot_level(model: FebModel, node: Node) -> None:
    """``plot_level``: PLOT_MAJOR_ITRS (every step) and PLOT_MUST_POINTS (the must points)
    are written as FEBio writes them; the others are a note (every step is written)."""
    level = node.text.strip()
    if level in PLOT_LEVELS:
        model.plot_level = PLOT_LEVELS[level]
    else:
        model.note(node, f"plot_level {level!r} not used: tissuesim writes every step")


def adaptive_table(model: FebModel, stepper: dict | None, plot: str | None) -> dict | None:
    """The scene's ``adaptive`` table for a step with a time stepper (None: fixed steps), with
    FEBio's defaults for what it does not give (dtmax 0.1, opt_iter 11, max_retries 5)."""
    if stepper is None:
        return None
    table: dict = {"dtmin": stepper.get("dtmin", 0.0)}
    if "curve" in stepper:
        number, node = stepper["curve"]
        curve = model.curves.get(number)
        if curve is None:
            raise node.error(f"load curve {number} is used but not defined in <LoadData>")
        kind = {"LINEAR": "linear", "STEP": "step"}.get(curve.interpolate)
        if kind is None or curve.extend not in ("CONSTANT", "EXTRAPOLATE"):
            raise node.error(
                f"a must-point curve with {curve.interpolate} interpolation and extend "
                f"{curve.extend}: tissuesim reads LINEAR and STEP curves, extend CONSTANT"
            )
        if len(curve.points) < 2:
            raise node.error("a must-point curve needs at least two points")
        table["dtmax_curve"] = [[float(t), float(v)] for t, v in curve.points]
        table["dtmax_interpolation"] = kind
    else:
        table["dtmax"] = stepper.get("dtmax", 0.1)
    for key in ("max_retries", "opt_iter", "aggressiveness", "cutback", "dtforce"):
        if key in stepper:
            table[key] = stepper[key]
    if plot == "must_points":
        table["frames"] = "must_points"
    return table


def run_steps(time_steps: int, step_size: float, table: dict | None) -> int:
    """The ``[run] steps`` of one FEBio step: its time_steps, or for adaptive steps an upper
    bound (the run ends at the step's end time): 10 times the steps of dtmax (or time_steps),
    and no more than dtmin allows."""
    if table is None:
        return time_steps
    duration = time_steps * step_size
    curve = table.get("dtmax_curve")
    positive = [v for _, v in curve if v > 0] if curve else [table["dtmax"]]
    dtmax = min(positive) if positive else duration / max(time_steps, 1)  # 0: no bound
    must = len(curve) if curve else 0
    cap = 10 * max(time_steps, math.ceil(duration / dtmax)) + must
    if table["dtmin"] > 0:
        cap = min(cap, math.ceil(duration / table["dtmin"]) + must + 1)
    return max(cap, time_steps)
