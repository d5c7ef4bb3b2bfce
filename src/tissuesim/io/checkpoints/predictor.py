"""The contact predictor's state in checkpoints (``contact/predict/predictor.py``), so that a
run in the interactive or accurate contact mode resumes bit-identically: the last step's
multipliers (the next contact solve's warm start, per pair), the barrier's pair weights learnt
so far, the contact forces carried into the next free motion, whether the next free motion is
Newton's, and the block of K^-1 kept for the compliance (solved again in another batch, its
columns could differ in the last bit). A predictor's own SuperLU factor (a step solver
without one: CG, AMG) is not kept: such runs resume within the solver's tolerance.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["capture_predictor", "restore_predictor"]


def capture_predictor(contact, solver, arrays: dict) -> dict | None:
    """The predictor's state (a JSON-able descriptor; arrays into ``arrays``), or None."""
    p = getattr(contact, "predictor", None)
    if p is None:
        return None
    meta: dict[str, Any] = {"refresh": bool(p.refresh)}
    for name, table in (("warm", p._warm), ("weights", p._weights)):
        keys = list(table)
        meta[f"{name}_keys"] = [list(k) for k in keys]
        if keys:
            arrays[f"predictor.{name}"] = np.array([table[k] for k in keys], dtype=float)
    if p._carried is not None:
        meta["carried_time"] = p._carried[0]
        arrays["predictor.carried"] = p._carried[1]
    c = p.compliance
    held = len(c._slot)
    direct = getattr(solver, "direct", None)
    if held and direct is not None and c._token == (id(direct), solver.version):
        meta["compliance_n"] = int(c._n)
        arrays["predictor.compliance_dofs"] = c._dofs
        arrays["predictor.compliance"] = c._G[:held, :held]
    return meta


def restore_predictor(contact, solver, meta: dict | None, arrays) -> None:
    """Make the predictor of ``contact`` what ``capture_predictor`` saw (after the solver)."""
    if not meta:
        return
    from tissuesim.time.contact_step import _predictor

    p = _predictor(contact)
    p.refresh = bool(meta["refresh"])
    for name in ("warm", "weights"):
        keys = [tuple(k) for k in meta[f"{name}_keys"]]
        values = list(np.array(arrays[f"predictor.{name}"])) if keys else []
        table = {
            k: (v.copy() if name == "warm" else float(v)) for k, v in zip(keys, values, strict=True)
        }
        setattr(p, "_warm" if name == "warm" else "_weights", table)
    if "carried_time" in meta:
        p.carry(meta["carried_time"], np.array(arrays["predictor.carried"]))
    direct = getattr(solver, "direct", None)
    if "compliance_n" in meta and direct is not None:
        c = p.compliance
        c._reset((id(direct), solver.version), meta["compliance_n"])
        dofs = np.array(arrays["predictor.compliance_dofs"], dtype=np.int64)
        c._dofs = dofs
        c._G = np.array(arrays["predictor.compliance"])
        c._slot = {int(j): i for i, j in enumerate(dofs.tolist())}
