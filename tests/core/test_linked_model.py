"""A body's model is made again with its couplings' vertex pairs once, at its next use, for
any number of springs and linear constraints added before (``bodies/couplings.py``)."""

from __future__ import annotations

import numpy as np

import tissuesim as ts
import tissuesim.bodies.couplings as couplings


def test_many_linear_constraints_make_the_model_once(monkeypatch):
    made = []
    real = couplings.Model

    def counting(*args, **kwargs):
        made.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(couplings, "Model", counting)
    sim = ts.Simulation(integrator="quasistatic", time_step=1.0)
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    body = sim.add_body("b", ts.box((0, 0, 0), (0.1, 0.05, 0.05), (4, 2, 2)), material)
    n = body.mesh.n_points
    for k in range(40):  # vertex k moves along x as vertex n - 1 - k does
        sim.add_linear_constraint([(k, 0, 1.0), (n - 1 - k, 0, -1.0)])
    assert made == []
    pattern = body.model.pattern.matrix(np.ones(body.model.pattern.nnz)).toarray()
    assert made == [1]
    for k in range(40):  # each pair's blocks are in the pattern
        assert pattern[3 * k, 3 * (n - 1 - k)] == 1.0
    body.model  # noqa: B018 - asked again: made no more
    assert made == [1]
