"""contact/geometry/edges.py: a surface's edges for ipctk, the empty surface included (ipctk.edges
took seconds on an empty int32 array, up to 37 s in a cut-and-fall run, and raised bad_alloc on an
empty int64 one)."""

from __future__ import annotations

import ipctk
import numpy as np

from tissuesim.contact.geometry.edges import triangle_edges


def test_an_empty_surface_has_no_edges():
    for dtype in (np.int32, np.int64):
        edges = triangle_edges(ipctk, np.zeros((0, 3), dtype=dtype))
        assert edges.shape == (0, 2)


def test_a_surface_has_the_edges_ipctk_gives():
    faces = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]], dtype=np.int32)
    edges = triangle_edges(ipctk, faces)
    assert np.array_equal(edges, ipctk.edges(faces))
    assert sorted(map(tuple, np.sort(edges, axis=1))) == [
        (0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]  # fmt: skip
