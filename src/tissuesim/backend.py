"""Which implementation assembles the elastic energy: fused Numba loops or batched NumPy.

    "numba": ``assembly/fused_p1.py``, one compiled loop per element (optional extra
             ``tissuesim[fast]``); 12-17x faster (docs/performance.md), compiled once, cached.
    "numpy": ``kinematics/p1.py`` + ``material.evaluate`` batched over all elements; always
             available, and the reference the Numba path is tested against.
    "auto":  numba when it is installed, else numpy.

The environment variable ``TISSUESIM_BACKEND`` overrides "auto" (e.g. to time or test the
fallback). Laws without a Numba kernel (fixed_corotated, user-defined ones) and evaluations
with a PSD-projected Hessian always take the NumPy path.
"""

from __future__ import annotations

import importlib.util
import os
from typing import Literal

from tissuesim.errors import InputError
from tissuesim.validate import short

__all__ = ["BACKENDS", "Backend", "numba_available", "resolve_backend"]

Backend = Literal["auto", "numba", "numpy"]
BACKENDS = ("auto", "numba", "numpy")


def numba_available() -> bool:
    return importlib.util.find_spec("numba") is not None


def resolve_backend(requested: str = "auto") -> tuple[str, str]:
    """The backend to use for ``requested`` and the reason, e.g. ("numba", "auto: ...")."""
    if requested not in BACKENDS:
        raise InputError(f"backend must be one of {BACKENDS}, not {short(requested)}")
    reason = "requested"
    if requested == "auto":
        env = os.environ.get("TISSUESIM_BACKEND", "auto").strip().lower() or "auto"
        if env not in BACKENDS:
            raise InputError(
                f"environment variable TISSUESIM_BACKEND must be one of {BACKENDS}, "
                f"not {short(env)}"
            )
        if env != "auto":
            requested, reason = env, "TISSUESIM_BACKEND"
        elif numba_available():
            requested, reason = "numba", "auto: numba installed"
        else:
            requested, reason = "numpy", "auto: numba not installed (pip install 'tissuesim[fast]')"
    if requested == "numba" and not numba_available():
        raise InputError(
            "backend 'numba' needs numba: pip install 'tissuesim[fast]', or use backend 'numpy'"
        )
    return requested, reason
