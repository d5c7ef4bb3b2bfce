"""The edges of a triangle surface for ipctk's CollisionMesh.

``ipctk.edges`` (1.6.1) on an empty array took 1.8-37 s for int32 faces and raised
``std::bad_alloc`` for int64 ones, where a surface has no triangles (a thin piece's surface
tried at a scale that leaves it none). An empty surface has no edges; others go to ipctk.
"""

from __future__ import annotations

import numpy as np

__all__ = ["triangle_edges"]


def triangle_edges(ipctk, faces: np.ndarray) -> np.ndarray:
    """The unique edges (e, 2) of triangles ``faces`` (t, 3), as ``ipctk.edges`` gives them."""
    faces = np.asarray(faces)
    if faces.size == 0:
        return np.zeros((0, 2), dtype=np.int32)
    return ipctk.edges(faces)
