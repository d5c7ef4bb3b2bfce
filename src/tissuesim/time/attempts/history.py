"""What a step does before and after its Newton solve for the bodies' internal variables: a
viscoelastic material's history (``materials/viscoelastic.py``) and Rayleigh damping
(``energies/damping.py``).

``time/attempts/retry.py`` calls ``begin_attempt`` before every attempt (halved ones too) and
``end_attempt`` after it: the history is frozen for the attempt from the last accepted state,
and updated once, only when the attempt converged; a rejected attempt leaves it as it was.
"""

from __future__ import annotations

from tissuesim.errors import InputError

__all__ = ["begin_attempt", "end_attempt", "has_internal_state"]


def _fem_models(system) -> list[tuple[int, object]]:
    bodies = getattr(system, "bodies", ())  # a System; anything else steps no bodies' state
    return [(j, b) for j, b in enumerate(bodies) if hasattr(b, "begin_step")]


def has_internal_state(model) -> bool:
    """True when a body's material keeps a history or the body is damped."""
    return hasattr(getattr(model, "material", None), "accept_step") or (
        getattr(model, "damping", None) is not None
    )


def begin_attempt(system, state, h: float) -> None:
    """Freeze every FEM body's history and damping for an attempt of ``h`` s from ``state``;
    a frame body with a viscoelastic material is refused (its points keep no history)."""
    for body in getattr(system, "bodies", ()):
        material = getattr(body, "material", None)
        if not hasattr(body, "begin_step") and hasattr(material, "accept_step"):
            raise InputError(
                f"{material.name} works on FEM bodies only (a frame body keeps no history at "
                "its points); give the frame body an elastic law"
            )
    for j, body in _fem_models(system):
        if has_internal_state(body):
            body.begin_step(state.x[system.config_slices[j]], h)


def end_attempt(system, outcome) -> None:
    """After an attempt: the histories updated at its state if it converged, else left."""
    for j, body in _fem_models(system):
        if has_internal_state(body):
            x = outcome.state.x[system.config_slices[j]] if outcome.converged else None
            body.end_step(x)
