"""The connective-tissue layer between organs: volume, membership, errors, contact facets."""

import numpy as np
import pytest

from tissuesim.coupling.layer import contact_facets, sample_between
from tissuesim.frames.sampling import IntegrationPoints
from tissuesim.mesh import box
from tissuesim.mesh.queries.locate import distance_to_boundary, inside_mesh

GAP = 0.1
LEFT = box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (4, 4, 4))
RIGHT = box((1.0 + GAP, 0.0, 0.0), (2.0 + GAP, 1.0, 1.0), (4, 4, 4))
SPACING = 0.02


def footprint(x):
    """The prism over the unit contact square: the gap slab without its fringe."""
    return ((x[:, 1:] >= 0.0) & (x[:, 1:] <= 1.0)).all(axis=1)


@pytest.fixture(scope="module")
def layer():
    return sample_between([LEFT, RIGHT], GAP, SPACING)


def test_layer_volume_between_two_boxes(layer):
    assert isinstance(layer, IntegrationPoints)
    cell = (GAP + 2.0 + 2.0 * GAP) / round((2.0 + 3.0 * GAP) / SPACING)  # grid cell along x
    assert (layer.volumes <= cell * (1.2 / round(1.2 / SPACING)) ** 2 * (1 + 1e-12)).all()
    # thickness = gap: the slab between the facing faces (gap * contact area) plus a fringe
    # around its rim, where points are within GAP of both edges: half a lens (two discs of
    # radius g, g apart) along the 4 edges, and a quarter lens of two balls at the 4 corners
    slab = GAP * 1.0
    fringe = 4.0 * (np.pi / 3.0 - np.sqrt(3.0) / 4.0) * GAP**2 + 5.0 * np.pi / 12.0 * GAP**3
    # measured: 0.12559 vs 0.12588 (-0.23%)
    assert layer.volume == pytest.approx(slab + fringe, rel=0.01)
    inner = sample_between([LEFT, RIGHT], GAP, SPACING, region=footprint)
    assert inner.volume == pytest.approx(slab, rel=0.01)  # measured: 0.1 (grid-aligned faces)
    # a grid that does not line up with the faces: the staggered sub-samples keep the thin
    # slab's volume within about 1% (measured -0.7%; a regular 2x2x2 sub-grid gave +6.8%)
    unaligned = sample_between([LEFT, RIGHT], GAP, 0.021, region=footprint)
    assert unaligned.volume == pytest.approx(slab, rel=0.02)
    assert "layer between" in inner.source and "in region" in inner.source


def test_every_point_outside_both_and_within_thickness_of_both(layer):
    x = layer.points
    assert not inside_mesh(LEFT, x).any() and not inside_mesh(RIGHT, x).any()
    assert (distance_to_boundary(LEFT, x) <= GAP).all()
    assert (distance_to_boundary(RIGHT, x) <= GAP).all()
    assert ((x[:, 0] >= 1.0) & (x[:, 0] <= 1.0 + GAP)).all()


def test_region_restricts(layer):
    def lower_half(x):
        return x[:, 1] < 0.5

    half = sample_between([LEFT, RIGHT], GAP, 0.04, region=lower_half)
    assert (half.points[:, 1] < 0.5).all()
    assert half.volume == pytest.approx(layer.volume / 2.0, rel=0.02)  # measured -0.8%
    with pytest.raises(ValueError, match=r"region must map points \(q, 3\) to a \(q,\) boolean"):
        sample_between([LEFT, RIGHT], GAP, SPACING, region=lambda x: x[:, 0])
    with pytest.raises(ValueError, match="region must be None or a callable"):
        sample_between([LEFT, RIGHT], GAP, SPACING, region=3)


def test_single_mesh_gets_a_shell():
    t = 0.1
    shell = sample_between([LEFT], t, 0.04)
    # the offset box minus the box: faces, quarter cylinders on the edges, ball eighths
    exact = 6.0 * t + 3.0 * np.pi * t**2 + 4.0 / 3.0 * np.pi * t**3
    assert shell.volume == pytest.approx(exact, rel=0.02)  # measured +0.08%
    assert not inside_mesh(LEFT, shell.points).any()


def test_empty_layer_messages():
    far = box((1.5, 0.0, 0.0), (2.5, 1.0, 1.0), (2, 2, 2))
    with pytest.raises(ValueError, match=r"are 0.5 apart .* more than 2 \* thickness = 0.2"):
        sample_between([LEFT, far], 0.1, 0.05)
    # gap 0.1 < 2 * 0.06: the layer is the slab 1.04 <= x <= 1.06, missed by a 1-sample grid
    with pytest.raises(ValueError, match="spacing 1 may be too coarse"):
        sample_between([LEFT, RIGHT], 0.06, 1.0, subsamples=1)
    with pytest.raises(ValueError, match="or the region excludes the whole layer"):
        sample_between([LEFT, RIGHT], GAP, 0.05, region=lambda x: x[:, 0] > 5.0)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf, "a"])
def test_thickness_and_spacing_must_be_positive_finite(bad):
    with pytest.raises(ValueError, match="sample_between: thickness must be"):
        sample_between([LEFT, RIGHT], bad, 0.05)
    with pytest.raises(ValueError, match="sample_between: spacing must be"):
        sample_between([LEFT, RIGHT], 0.1, bad)


def test_meshes_argument():
    with pytest.raises(ValueError, match=r"for one mesh use \[mesh\]"):
        sample_between(LEFT, 0.1, 0.05)
    with pytest.raises(ValueError, match="non-empty sequence"):
        sample_between([], 0.1, 0.05)
    with pytest.raises(ValueError, match=r"meshes\[1\] must be a tissuesim Mesh"):
        sample_between([LEFT, "right"], 0.1, 0.05)


def test_contact_facets_are_the_facing_faces(layer):
    left = contact_facets(LEFT, layer.points, 0.05)
    right = contact_facets(RIGHT, layer.points, 0.05)

    def as_set(f):
        return {tuple(sorted(row)) for row in f.tolist()}

    assert as_set(left) == as_set(LEFT.facet_sets["xmax"])
    assert as_set(right) == as_set(RIGHT.facet_sets["xmin"])
    assert contact_facets(LEFT, np.zeros((0, 3)), 0.05).shape == (0, 3)
    with pytest.raises(ValueError, match="contact_facets: distance must be"):
        contact_facets(LEFT, layer.points, 0.0)
    with pytest.raises(ValueError, match=r"points must be a \(q, 3\) array"):
        contact_facets(LEFT, np.zeros((2, 2)), 0.1)
