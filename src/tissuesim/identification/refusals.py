"""What the sensitivities take (``sensitivity.py``): the runs, contacts, rigid bodies and
lagged terms whose derivative follows the steps as solved; the others are refused in one line
(``check_taken``), and ``refusal`` says why without raising (FEBio's optimisation files then
use forward differences: ``febio/optimize/run.py``)."""

from __future__ import annotations

from tissuesim.errors import InputError

__all__ = ["check_taken", "refusal"]


def refusal(sim, what: str) -> str | None:
    """Why the sensitivities of ``sim``'s run are not taken (the one-line message), or None."""
    try:
        check_taken(sim, what)
    except InputError as exc:
        return str(exc)
    return None


def check_taken(sim, what: str) -> None:
    s = sim.system
    if sim.integrator not in ("quasistatic", "backward_euler", "newmark"):
        raise InputError(
            f"{what}: sensitivities are taken of quasistatic, backward_euler and newmark runs, "
            f"not {sim.integrator!r}"
        )
    for pair in s.penalty_contacts:
        lagged = [why for why, on in (  # (a rigid wall is a pair with no areas or ties)
            ("augmented", pair.augmented), ("friction", pair.friction > 0),
            ("sticky", getattr(pair, "sticky", False)),
        ) if on]  # fmt: skip
        if lagged:
            raise InputError(
                f"{what}: penalty contact {pair.name!r} is {', '.join(lagged)}: its lagged "
                "terms are not differentiated yet (penalty contact without them is): use "
                "penalty contact without them, barrier contact, or finite differences of "
                "whole runs"
            )
    if s.rigid and (sim.integrator != "quasistatic" or getattr(s, "joints", None)):
        raise InputError(
            f"{what}: sensitivities of runs with rigid bodies are taken quasistatic and "
            "without rigid joints: finite differences of whole runs"
        )
    if s.contact is not None and s.contact.settings.mode == "interactive":
        raise InputError(
            f"{what}: an interactive contact step is a prediction, not the minimum the "
            "derivative differentiates: set_contact(mode='barrier' or 'accurate')"
        )
    for name, body in sim.bodies.items():
        if body.kind != "fem":
            raise InputError(f"{what}: body {name!r} is not a FEM body (frames are not taken)")
        model = body.model
        if hasattr(model, "lagged_materials") and model.lagged_materials():
            from tissuesim.kinematics.nodal import NodalKinematics

            parts = [model] if model.parts is None else model.parts
            if any(getattr(p.material, "lagged", False) and not (
                    isinstance(p.kinematics, NodalKinematics)
                    and hasattr(p.material, "lag_derivatives")) for p in parts):  # fmt: skip
                raise InputError(
                    f"{what}: body {name!r}'s bond recruitment is lagged in a mixture or on "
                    "shells, whose lag the sensitivities do not follow: use finite differences "
                    "of whole runs (gradients = 'differences')"
                )
