"""A FEBio surface's facet lying in two bodies is loaded once (febio/surface_owners.py), by
the body it faces, as FEBio loads each facet once along its own normal: sh60's quads under a
rigid block glued on a shell were loaded in both, the shell's pressure pushing down and the
block's (oriented outward from the block) pushing up, and cancelled (the block sank 5 % less
than FEBio's; with one owner the run is FEBio's to 7e-14, benchmarks/results)."""

from __future__ import annotations

import numpy as np

from tissuesim.febio.surface_owners import facet_owners

#: a unit cube below z = 0 (nodes 0-7) and one above it (4-11), sharing the face z = 0
POINTS = np.array(
    [[0, 0, -1], [1, 0, -1], [1, 1, -1], [0, 1, -1], [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
     [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float,
)  # fmt: skip
BELOW = np.array([[0, 1, 2, 3, 4, 5, 6, 7]])
ABOVE = np.array([[4, 5, 6, 7, 8, 9, 10, 11]])


def test_a_shared_facet_goes_to_the_body_behind_its_normal():
    up = np.array([[4, 5, 6, 7]])  # counter-clockwise seen from +z: its normal is +z
    down = up[:, ::-1]
    assert facet_owners(POINTS, up, [BELOW, ABOVE]).tolist() == [0]
    assert facet_owners(POINTS, up, [ABOVE, BELOW]).tolist() == [1]  # whatever the order
    assert facet_owners(POINTS, down, [BELOW, ABOVE]).tolist() == [1]
    triangle = np.array([[4, 5, 6]])  # a tri3 surface's facet
    assert facet_owners(POINTS, triangle, [ABOVE, BELOW]).tolist() == [1]


def test_a_facet_of_one_body_stays_with_it_and_one_of_none_is_dropped():
    facets = np.array([[0, 3, 2, 1], [8, 9, 10, 11], [0, 1, 9, 8]])  # bottom, top, across
    assert facet_owners(POINTS, facets, [BELOW, ABOVE]).tolist() == [0, 1, -1]
    # two bodies holding the facet's nodes but neither as a face pointing its way: the first
    flat = np.array([[4, 5, 6, 7]])
    twice = np.array([[4, 5, 6, 7, 4, 5, 6, 7]])  # a degenerate cell in the plane
    assert facet_owners(POINTS, flat, [twice, twice]).tolist() == [0]
