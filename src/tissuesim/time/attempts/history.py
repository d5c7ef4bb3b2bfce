"""What a step does before and after its Newton solve for the bodies' internal variables: a
viscoelastic material's history (``materials/viscoelastic.py``) and Rayleigh damping
(``energies/damping.py``).

``time/attempts/retry.py`` calls ``begin_attempt`` before every attempt (halved ones too) and
``end_attempt`` after it: the history is frozen for the attempt from the last accepted state,
and updated once, only when the attempt converged; a rejected attempt leaves it as it was.

The lagged terms of FEBio's contacts and joints (penalty pairs' and rigid walls' multipliers,
current-area weights, sticky ties and friction, rigid joints' multipliers) are kept the same
way: a rejected attempt's augmentations are undone, so the halved step starts from the last
accepted multipliers, as FEBio's restart from its dump of the step's start does.
"""

from __future__ import annotations

import copy

from tissuesim.errors import InputError

__all__ = ["begin_attempt", "end_attempt", "has_internal_state", "keep_lags", "restore_lags"]


def _fem_models(system) -> list[tuple[int, object]]:
    bodies = getattr(system, "bodies", ())  # a System; anything else steps no bodies' state
    return [(j, b) for j, b in enumerate(bodies) if hasattr(b, "begin_step")]


def has_internal_state(model) -> bool:
    """True when a body's material keeps a history or the body is damped."""
    return hasattr(getattr(model, "material", None), "accept_step") or (
        getattr(model, "damping", None) is not None
    )


#: the lagged fields of a penalty pair, its passes, a rigid wall and a rigid joint
_LAGGED = ("multipliers", "weights", "tie", "friction", "augmentations", "last_gap", "stalls")


def _lag_holders(system) -> list:
    holders = []
    for pair in getattr(system, "penalty_contacts", ()) or ():
        holders.append(pair)
        holders.extend(pair.passes)
    holders.extend(getattr(system, "joints", ()) or ())
    return holders


def keep_lags(system) -> list:
    """A copy of every lagged field (restored by ``restore_lags`` after a rejected attempt)."""
    kept = []
    for holder in _lag_holders(system):
        fields = {k: copy.deepcopy(getattr(holder, k)) for k in _LAGGED if hasattr(holder, k)}
        kept.append((holder, fields))
    return kept


def restore_lags(kept: list) -> None:
    for holder, fields in kept:
        for key, value in fields.items():
            setattr(holder, key, copy.deepcopy(value))


def begin_attempt(system, state, h: float) -> None:
    """Freeze every FEM body's history and damping for an attempt of ``h`` s from ``state``,
    and keep the contacts' and joints' lagged terms; a frame body with a viscoelastic material
    is refused (its points keep no history)."""
    if hasattr(system, "penalty_contacts"):
        system._attempt_lags = keep_lags(system)
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
    """After an attempt: the histories updated at its state if it converged, else left; the
    lagged terms kept by ``begin_attempt`` restored if it did not converge."""
    kept = getattr(system, "_attempt_lags", None)
    if kept is not None:
        system._attempt_lags = None
        if not outcome.converged:
            restore_lags(kept)
    for j, body in _fem_models(system):
        if has_internal_state(body):
            x = outcome.state.x[system.config_slices[j]] if outcome.converged else None
            body.end_step(x)
