"""A frame body attached to a FEM body where it touches it: the tissue's attachment energy
(``attachment.py``) for any frame body, not only the tissue sampled between organs.

Points are sampled on the FEM body's boundary triangles that face the frame body's integration
points (``layer.contact_facets``, within ``distance``), no farther apart than the frame body's
sample spacing, each barycentric in a FEM tetrahedron and carried by the frames (eq. 3). The
energy sum_s k_s / 2 |p_s - y_s|^2 is zero at rest; its gradient, Hessian and FEM-frame cross
blocks are the tissue's (``system.py``). The force the frame body exerts on the FEM body,
sum_s k_s (p_s - y_s) (N), is reported under the attachment's name.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tissuesim.coupling.attachment import Attachment
from tissuesim.errors import InputError

__all__ = ["FrameAttachment", "frame_attachment"]


@dataclass(frozen=True, eq=False)
class FrameAttachment:
    """Where frame body ``frames`` holds FEM body ``fem``: rest points (S, 3) on the FEM
    surface, their FEM cells and barycentric coordinates, stiffness (S,) N/m."""

    name: str
    fem: str
    frames: str
    points: np.ndarray
    cells: np.ndarray
    barycentric: np.ndarray
    stiffness: np.ndarray

    def build(self, fem_index: int, frame_index: int, frame_model) -> Attachment:
        """The attachment of a system in which the bodies have these indices."""
        try:
            embedding = frame_model.embed(self.points, f"attachment point of {self.name!r}")
        except ValueError as exc:
            raise InputError(
                f"attach {self.frames!r} to {self.fem!r}: {exc}. The frames must reach the "
                f"contact points: add frames near the contact or raise radius_factor"
            ) from None
        ids = np.arange(len(self.points))
        return Attachment(
            fem_index,
            self.points,
            self.cells,
            self.barycentric,
            self.stiffness,
            embedding,
            ids,
            frame_index,
        )


def frame_attachment(
    name: str, fem: str, mesh, frames: str, samples, *, distance: float, stiffness_per_area: float
) -> FrameAttachment:
    from tissuesim.coupling.layer import contact_facets
    from tissuesim.coupling.tissue import _facet_samples
    from tissuesim.mesh.queries.locate import closest_boundary_points

    if mesh.dim != 3:
        raise InputError(f"attach: body {fem!r} is {mesh.dim}D; frame bodies attach to 3D bodies")
    spacing = float(np.cbrt(np.median(samples.volumes)))
    facets = contact_facets(mesh, samples.points, distance)
    if not len(facets):
        raise InputError(
            f"attach {frames!r} to {fem!r}: no boundary triangle of {fem!r} faces an "
            f"integration point of {frames!r} within distance {distance:g} m; move the bodies "
            "together or give a larger distance"
        )
    points, area = _facet_samples(mesh.points, facets, spacing)
    where = closest_boundary_points(mesh, points)
    return FrameAttachment(
        name,
        fem,
        frames,
        where.positions,
        where.cells,
        where.barycentric,
        stiffness_per_area * area,
    )
