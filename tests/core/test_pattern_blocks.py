"""The node-blocked sparsity pattern (FEM stencils, merged node by node) is the same pattern
with the same scatter maps as the generic DOF-level merge."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.assembly.pattern import SparsityPattern, _node_block
from tissuesim.kinematics.nodal import NodalKinematics

NO_EXTRA = (np.zeros(0, np.int64), np.zeros(0, np.int64))  # forces the generic path


@pytest.mark.parametrize(
    "mesh",
    [
        ts.rectangle((0, 0), (1, 0.5), (5, 3)),
        ts.box((0, 0, 0), (1, 0.4, 0.3), (4, 3, 2)),
        ts.ellipsoid((0, 0, 0), (1.0, 0.6, 0.4), 3),
    ],
    ids=["triangles", "box", "ellipsoid"],
)
def test_blocked_pattern_equals_the_generic_one(mesh):
    d = mesh.dim
    stencil = NodalKinematics.dof_stencil(mesh.cells, d)
    n = mesh.n_points * d
    assert _node_block(n, [stencil]) == d
    fast = SparsityPattern.from_stencils(n, [stencil])
    slow = SparsityPattern.from_stencils(n, [stencil], NO_EXTRA)
    assert np.array_equal(fast.indptr, slow.indptr)
    assert np.array_equal(fast.indices, slow.indices)
    assert np.array_equal(fast.diagonal, slow.diagonal)
    assert np.array_equal(fast.scatters[0], slow.scatters[0])
    # and it assembles the same matrix: random local blocks scattered both ways
    blocks = np.random.default_rng(0).normal(size=(len(stencil), stencil.shape[1] ** 2))
    a, b = np.zeros(fast.nnz), np.zeros(slow.nnz)
    fast.accumulate(a, 0, blocks)
    slow.accumulate(b, 0, blocks)
    assert np.array_equal(a, b)


def test_stencils_that_are_not_whole_nodes_take_the_generic_path():
    stencil = np.array([[0, 1, 2, 4, 5, 6]])  # the second "node" starts at DOF 4
    assert _node_block(9, [stencil]) == 0
    p = SparsityPattern.from_stencils(9, [stencil])
    assert p.nnz == 36 + 3  # the 6 x 6 block and the diagonal of DOFs 3, 7, 8
