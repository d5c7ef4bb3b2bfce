"""A step's start with the kerf ahead of a blade in contact opened (contact/cut/blade_clearance.py):
the surface vertices in the blade's path are moved to their side of its plane, at least the gap
from it; nothing far from the path moves; a kerf already open needs nothing. And on the liver
resected by an instrument, the steps start with the blade at its target instead of pulling it
in by a penalty inside Newton."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import tissuesim as ts
from tissuesim.contact.cut.blade_clearance import clearance
from tissuesim.contact.cut.surface import BLADE_GAP, cut_surface
from tissuesim.mesh.cutting.virtual_nodes import PlanarCut, virtual_node_cut

DHAT = 0.01
GAP = BLADE_GAP * DHAT
POINT, NORMAL = np.array([0.47, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])
#: a blade edge across y = 0.15 .. 0.25 going down from z = 0.3 to 0.2 in the plane x = 0.47
PATH = [np.array([[0.47, 0.15, z], [0.47, 0.25, z]]) for z in np.linspace(0.3, 0.2, 5)]


def _cut_box():
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.4, 0.3), (10, 4, 3))
    cut = PlanarCut.swept_segment(
        (0.47, -1.0, 1.0), (0.47, 2.0, 1.0), (0.47, -1.0, -1.0), (0.47, 2.0, -1.0)
    )
    vn = virtual_node_cut(mesh.points, mesh.cells, [cut])
    cm = vn.to_mesh(mesh)
    W, _ = cut_surface(cm, DHAT, BLADE_GAP)
    # the two pieces: the one holding the node at x = 1 is on the + side
    n = len(cm.points)
    cells = cm.cells
    rows = np.repeat(np.arange(len(cells)), cells.shape[1])
    A = sp.csr_matrix((np.ones(rows.size), (rows, cells.ravel())), shape=(len(cells), n))
    _, label = sp.csgraph.connected_components(A.T @ A, directed=False)
    plus = label == label[np.argmax(cm.points[:, 0])]
    copies = vn.side != 0
    return cm, W, plus, vn.cells[copies], vn.level[copies]


def _in_path(V: np.ndarray, margin: float) -> np.ndarray:
    return (np.abs(V[:, 1] - 0.2) <= 0.05 + margin) & (np.abs(V[:, 2] - 0.25) <= 0.05 + margin)


def test_the_kerf_is_opened_on_the_blades_path_only():
    """The + piece shifted 1.5 gaps across the plane (its cut face 0.5 gap on the - side):
    every surface vertex in the blade's path ends at least the gap on its side, those of the
    - piece already there do not move, and vertices more than a cell beyond the path do not
    move."""
    cm, W, plus, cells, level = _cut_box()
    X = cm.points.copy()
    X[plus] -= 1.5 * GAP * NORMAL
    V = W @ X
    move = clearance(X, cells, level, W, V, PATH, POINT, NORMAL, GAP, 2 * GAP)
    assert move is not None
    V1 = W @ (X + move)
    d1 = (V1 - POINT) @ NORMAL
    side = np.where(W @ plus.astype(float) > 0.5, 1.0, -1.0)
    near = _in_path(V, 0.0) & (np.abs((V - POINT) @ NORMAL) < 3 * GAP)
    assert near.sum() > 10
    assert np.all(side[near] * d1[near] >= GAP * (1 - 1e-9))
    assert np.allclose(V1[side < 0], V[side < 0])  # the - face was clear already
    far = ~_in_path(V, 0.1 + 2 * GAP + 1e-9)  # a cell (0.1 m) beyond the path and margin
    assert far.sum() > 10
    assert np.allclose(V1[far], V[far])
    # only along the plane's normal
    assert np.allclose(move[:, 1:], 0.0) and np.all(move[:, 0] >= 0.0)


def test_an_open_kerf_needs_nothing():
    cm, W, plus, cells, level = _cut_box()
    X = cm.points
    assert clearance(X, cells, level, W, W @ X, PATH, POINT, NORMAL, 0.99 * GAP, GAP) is None
    # a blade that sweeps no area has no path
    still = [PATH[0], PATH[0]]
    assert clearance(X, cells, level, W, W @ X, still, POINT, NORMAL, 2 * GAP, GAP) is None


def test_the_liver_steps_start_with_the_blade_at_its_target():
    """The coarse liver resection by an instrument: where the hanging lobe closes the kerf
    ahead of the blade (from about step 19), the step starts with the kerf opened and the
    blade at its target; without that every such step pulled the blade in by a penalty inside
    Newton (4 of the first 25 steps). A step in which the kerf's end lies in the blade's path
    still does (one here)."""
    import tomllib

    pytest.importorskip("ipctk")
    import tissuesim.time.steps as steps
    from tissuesim.cli import example_path
    from tissuesim.scene.loader import build_scene

    data = tomllib.loads(example_path("liver_instrument").read_text())
    data["bodies"][0]["mesh"]["divisions"] = 6
    sim = build_scene(data, base_dir=example_path("liver_instrument").parent).simulation
    pulled, cleared = [], []
    original_pull, original_clear = steps._step_with_moving_obstacles, steps._cleared_starts

    def pull(*args, **kwargs):
        pulled.append(sim.time)
        return original_pull(*args, **kwargs)

    def clear(*args, **kwargs):
        starts = original_clear(*args, **kwargs)
        cleared.append(bool(starts))
        return starts

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(steps, "_step_with_moving_obstacles", pull)
        mp.setattr(steps, "_cleared_starts", clear)
        for _ in range(25):
            assert sim.step().converged
            assert not sim.system.contact.intersecting(sim.state.x)
    assert sum(cleared) >= 2
    assert len(pulled) <= 2


def test_a_vertex_on_a_node_both_sides_share_is_moved_by_its_other_nodes():
    """Where a cut's copies stay joined (at its front) a node belongs to copies on both sides:
    it stays where it is and the vertex's nodes on one side move further for it, when they
    carry at least MIN_SIDED of its weight; a vertex held mostly by the shared node is left."""
    from tissuesim.contact.cut.blade_clearance import MIN_SIDED

    # a + copy (nodes 0, 1, 2 on the + side, node 3 virtual) and a - copy sharing node 3
    x = np.array([[1.0, 0, 0], [1.0, 1, 0], [1.0, 0, 1], [-1.0, 0, 0],
                  [-1.0, 1, 0], [-1.0, 0, 1], [-1.0, 1, 1]])  # fmt: skip
    cells = np.array([[0, 1, 2, 3], [4, 5, 6, 3]])
    level = np.array([[1.0, 1.0, 1.0, -1.0], [1.0, 1.0, 1.0, 1.0]])  # distance x side
    W = sp.csr_matrix(np.array([[0.5, 0, 0, 0.5, 0, 0, 0], [0.1, 0, 0, 0.9, 0, 0, 0]]))
    V = W @ x
    blades = [np.array([[0.0, -5, -5], [0.0, 5, -5]]), np.array([[0.0, -5, 5], [0.0, 5, 5]])]
    gap = 0.01
    move = clearance(x, cells, level, W, V, blades, np.zeros(3), np.array([1.0, 0, 0]), gap, 0.0)
    assert move is not None
    assert np.allclose(move[1:], 0.0)  # node 3 shared: kept; nodes 1, 2 hold no vertex here
    after = W @ (x + move)
    assert after[0, 0] == pytest.approx(gap)  # node 0 moved 2 gaps for its half weight
    assert 0.1 < MIN_SIDED  # the second vertex is held by the shared node: not moved for it
    assert after[1, 0] == pytest.approx(V[1, 0] + 0.1 * move[0, 0])
