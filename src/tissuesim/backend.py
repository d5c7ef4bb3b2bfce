"""Which implementation assembles the elastic energy: fused Numba loops or batched NumPy.

    "numba": ``assembly/fused_p1.py``, one compiled loop per element (optional extra
             ``tissuesim[fast]``); 12-17x faster (docs/performance.md), compiled once, cached.
    "numpy": ``kinematics/p1.py`` + ``material.evaluate`` batched over all elements; always
             available, and the reference the Numba path is tested against.
    "auto":  numba when it is installed and the mesh is not small, else numpy: below
             SMALL_MESH_CELLS cells NumPy is faster over a short run, because Numba's fixed
             cost per process (importing it and loading its cached kernels, 0.4-0.5 s) takes
             more than about 250 evaluations of such a mesh to repay
             (``benchmarks/results/backend_threshold.md``).

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

__all__ = ["BACKENDS", "Backend", "SMALL_MESH_CELLS", "numba_available", "resolve_backend"]

Backend = Literal["auto", "numba", "numpy"]
BACKENDS = ("auto", "numba", "numpy")
#: cells per dimension below which "auto" takes NumPy (measured on a quiet 2-core machine,
#: ``benchmarks/results/backend_threshold.md``): Numba's fixed cost per process is 0.4-0.5 s and
#: it saves 1.0 ms per evaluation at 512 triangles, 0.8 ms at 162 tetrahedra, 5.9 ms at 4,050
#: triangles, 4.8 ms at 1,296 tetrahedra; at these thresholds about 250 evaluations (20-50
#: Newton steps) repay it, below them more: a short run of a small scene is faster on NumPy
SMALL_MESH_CELLS = {2: 1000, 3: 500}


def numba_available() -> bool:
    return importlib.util.find_spec("numba") is not None


def resolve_backend(
    requested: str = "auto", cells: int | None = None, dim: int | None = None
) -> tuple[str, str]:
    """The backend to use for ``requested`` and the reason, e.g. ("numba", "auto: ...");
    ``cells`` and ``dim``: the mesh's size, so that "auto" keeps small meshes on NumPy."""
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
        elif numba_available() and cells is not None and cells < SMALL_MESH_CELLS.get(dim, 0):
            requested = "numpy"
            reason = (
                f"auto: a small mesh ({cells} cells < {SMALL_MESH_CELLS[dim]}), faster with "
                "NumPy than with Numba's fixed cost per run"
            )
        elif numba_available():
            requested, reason = "numba", "auto: numba installed"
        else:
            requested, reason = "numpy", "auto: numba not installed (pip install 'tissuesim[fast]')"
    if requested == "numba" and not numba_available():
        raise InputError(
            "backend 'numba' needs numba: pip install 'tissuesim[fast]', or use backend 'numpy'"
        )
    return requested, reason
