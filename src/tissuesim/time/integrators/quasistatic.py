"""Quasistatic load stepping needs supports: x_{n+1} = argmin_x E(x) - f(t_{n+1}) . x has no
inertia, so a body must be held against rigid motions by its prescribed DOFs (the step itself
is ``time/steps.py``'s implicit step without inertia)."""

from __future__ import annotations

from tissuesim.errors import InputError

__all__ = ["check_supported"]


def check_supported(model) -> None:
    """Refuse a quasistatic solve that nothing holds (SciPy would return finite garbage)."""
    d = model.mesh.dim
    needed = d * (d + 1) // 2  # rigid motions: 3 in 2D, 6 in 3D
    if model.prescribed.dofs.size < needed:
        raise InputError(
            f"a quasistatic solve needs prescribed displacements that remove the {needed} rigid "
            f"motions of a {d}D body; this model prescribes {model.prescribed.dofs.size} DOFs. "
            "Add a [[dirichlet]] condition (e.g. clamp one side) or use backward_euler."
        )
