"""The predictor's compiled broad phase (contact/predict/broad_phase.py, box_grid.py) finds
exactly the candidate pairs ipctk's does: the same boxes, overlap test and filters (shared
vertices, pairs left out in the pair table, obstacles never with obstacles), in 3D and 2D,
over sweeps short and long, with a large obstacle face and with self-contact."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.predict import rows

pytest.importorskip("ipctk")
pytest.importorskip("numba")  # without numba the predictor uses ipctk's (nothing to compare)

from tissuesim.contact.obstacles import plane, sphere  # noqa: E402
from tissuesim.contact.predict.broad_phase import compiled_candidates  # noqa: E402

MATERIAL = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)


def _canonical(parts) -> dict[int, set]:
    """{kind: set of stencils}, two edges in one order whatever the search's."""
    out = {}
    for kind, stencils in parts:
        stencils = np.array(stencils)
        if kind == 1:
            e0, e1 = np.sort(stencils[:, :2], axis=1), np.sort(stencils[:, 2:], axis=1)
            swap = (e0[:, 0] > e1[:, 0]) | ((e0[:, 0] == e1[:, 0]) & (e0[:, 1] > e1[:, 1]))
            e0[swap], e1[swap] = e1[swap].copy(), e0[swap].copy()
            stencils = np.column_stack([e0, e1])
        out.setdefault(kind, set()).update(map(tuple, stencils.tolist()))
    return out


def _ipctk_candidates(contact, V0, V1, inflation, monkeypatch) -> dict[int, set]:
    with monkeypatch.context() as m:
        m.setattr(rows, "compiled_candidates", lambda *args: None)
        return _canonical(rows._candidates(contact, V0, V1, inflation))


def _three_d_scene(pairs=None):
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01)
    sim.add_body("low", ts.box((0, 0, 0), (0.1, 0.1, 0.03), (5, 5, 2)), MATERIAL, density=1e3)
    upper = ts.box((0.02, 0.02, 0.0305), (0.08, 0.08, 0.06), (3, 3, 2))
    sim.add_body("high", upper, MATERIAL, density=1e3)
    sim.set_contact(dhat=1e-3, friction=0.2, pairs=pairs)
    sim.add_obstacle("table", plane((0.0, 0.0, -5e-4), (0, 0, 1), 1.0))
    sim.add_obstacle("probe", sphere((0.05, 0.05, 0.075), 0.01, refinement=2))
    return sim.system.contact


@pytest.mark.parametrize("pairs", [None, [ts.ContactPair("low", "high", enabled=False)]])
@pytest.mark.parametrize("motion", [2e-4, 5e-3, 3e-2])
@pytest.mark.parametrize("inflation", [0.0, 1.5e-3])
def test_the_compiled_broad_phase_finds_ipctks_pairs_in_3d(pairs, motion, inflation, monkeypatch):
    contact = _three_d_scene(pairs)
    V0 = np.asfortranarray(contact.rest)
    rng = np.random.default_rng(int(1e4 * motion))
    V1 = np.asfortranarray(V0 + rng.normal(scale=motion, size=V0.shape))
    found = compiled_candidates(contact, V0, V1, inflation)
    assert found is not None
    ours = _canonical(found)
    theirs = _ipctk_candidates(contact, V0, V1, inflation, monkeypatch)
    assert ours == theirs
    assert sum(len(v) for v in ours.values()) > 0


def test_the_compiled_broad_phase_finds_ipctks_pairs_in_2d(monkeypatch):
    sim = ts.Simulation(integrator="backward_euler", time_step=0.01)
    sim.add_body("low", ts.rectangle((0, 0), (1, 0.3), (8, 3)), MATERIAL, density=100.0)
    sim.add_body("high", ts.rectangle((0.2, 0.31), (0.8, 0.6), (5, 3)), MATERIAL, density=100.0)
    sim.set_contact(dhat=0.02)
    contact = sim.system.contact
    V0 = np.asfortranarray(contact.rest)
    V1 = np.asfortranarray(V0 + np.random.default_rng(5).normal(scale=0.03, size=V0.shape))
    ours = _canonical(compiled_candidates(contact, V0, V1, 0.01))
    assert ours == _ipctk_candidates(contact, V0, V1, 0.01, monkeypatch)
    assert set(ours) == {2} and len(ours[2]) > 0
