"""An instrument as the blade (``add_cut("scalpel", ..., body=..., edge=...)``): an obstacle's
triangle cuts as the same blade given as a function of t does (``contact=False``: it passes
through the body it cuts while keeping contact with the others), follows a live drive between
steps (off its first plane too) and reports what the instrument feels. In contact with the body
it cuts (the default): ``test_blade_contact.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.contact.obstacles import sphere
from tissuesim.errors import InputError
from tissuesim.frames.sampling import Surface

pytest.importorskip("ipctk")

#: a scalpel's flat blade in the plane y = 0.015 (through the cells), its edge down to z = 0.025
CORNERS = np.array([[-0.06, 0.015, 0.025], [-0.02, 0.015, 0.06], [-0.06, 0.015, 0.06]])


def _block(contact: bool = True) -> ts.Simulation:
    mesh = ts.box((0, 0, 0), (0.1, 0.04, 0.04), (10, 4, 4))
    sim = ts.Simulation(mesh, ts.NeoHookean(youngs_modulus=3e3, poisson_ratio=0.4),
                        density=1000.0, integrator="quasistatic", time_step=0.25)  # fmt: skip
    sim.fix(ts.select.vertices_on_plane(mesh, axis=2, value=0.0), name="table")
    if contact:
        sim.set_contact(dhat=1e-4)
    return sim


def _scalpel(sim: ts.Simulation, translation) -> str:
    return sim.add_obstacle("scalpel", Surface(CORNERS, np.array([[0, 1, 2]])),
                            translation=translation)  # fmt: skip


def test_an_instruments_blade_cuts_as_the_same_blade_given_as_a_function():
    def move(t):
        return np.array([0.2 * t, 0.0, 0.0])

    by_obstacle = _block()
    _scalpel(by_obstacle, move)
    by_obstacle.add_cut("scalpel", 0.0, math.inf, body="body", name="incision", contact=False)
    by_function = _block()
    _scalpel(by_function, move)  # the same instrument in the scene, not the blade
    by_function.set_contact(dhat=1e-4, pairs=[{"bodies": ["body", "scalpel"], "enabled": False}])
    by_function.add_cut(lambda t: CORNERS + move(t), 0.0, 1.0, body="body", name="incision")
    for _ in range(4):
        a, b = by_obstacle.step(), by_function.step()
    cut_a, cut_b = a.extra["cuts"]["incision"], b.extra["cuts"]["incision"]
    # the blade went through the whole block (0.1 m) from the top down to z = 0.025
    assert cut_a["area_m2"] == pytest.approx(0.1 * 0.015, rel=1e-9)
    assert cut_a["area_m2"] == pytest.approx(cut_b["area_m2"], rel=1e-12)
    assert np.allclose(by_obstacle.positions, by_function.positions, rtol=0, atol=1e-12)
    table = by_obstacle.system.contact.table
    i, j = table.names.index("body"), table.names.index("scalpel")
    assert not table.enabled[i, j]  # it passes through what it cuts


def test_a_live_driven_blade_cuts_where_it_is_driven_and_reports_what_it_feels():
    """Driven along x step by step: the cut grows by the swept area per step; with a
    toughness G the instrument feels G dA / ds against its motion (no contact on it)."""
    sim = _block()
    _scalpel(sim, None)
    sim.add_cut("scalpel", 0.0, math.inf, body="body", name="incision", toughness=100.0,
                contact=False)  # fmt: skip
    areas, at = [], 0.0
    for k in range(1, 6):
        target = 0.025 * k + 0.04
        sim.drive_obstacle("scalpel", translation=(target, 0.0, 0.0))
        record = sim.step()
        travel, at = target - at, target
        cut = record.extra["cuts"]["incision"]
        areas.append(cut["area_m2"])
        if cut["new_area_m2"] > 0:
            force = np.asarray(record.extra["forces"]["incision"])
            expected = 100.0 * cut["new_area_m2"] / travel  # G dA / ds, against +x
            assert force[0] == pytest.approx(-expected, rel=1e-9)
            assert np.allclose(force[1:], 0.0, atol=1e-9 * expected)
    # the cut grows step by step, cells swept through; the blade's tip leaves the block at
    # x = 0.105 in the last step
    assert np.all(np.diff(areas) > 0) and areas[-1] == pytest.approx(0.1 * 0.015, rel=1e-9)
    # driven out of its first plane, the instrument goes on cutting along its new path
    tool = sim.organ_cuts[0]
    sim.drive_obstacle("scalpel", translation=(0.2, 0.01, 0.0))
    record = sim.step()
    assert record.converged and tool.curved
    assert record.extra["cuts"]["incision"]["area_m2"] >= areas[-1]


def test_an_obstacle_blade_is_refused_in_one_line_when_it_cannot_be_one():
    sim = _block()
    sim.add_obstacle("probe", sphere((0.05, 0.02, 0.1), 0.01))
    with pytest.raises(InputError, match="no obstacle 'knife'"):
        sim.add_cut("knife", 0.0, 1.0, body="body")
    with pytest.raises(InputError, match="give edge"):
        sim.add_cut("probe", 0.0, 1.0, body="body")
    with pytest.raises(InputError, match="2 or 3 distinct vertices"):
        sim.add_cut("probe", 0.0, 1.0, body="body", edge=(0, 0))
    with pytest.raises(InputError, match="give body"):
        sim.add_cut("probe", 0.0, 1.0, edge=(0, 1))
    with pytest.raises(InputError, match="end must be a finite time"):
        sim.add_cut(lambda t: CORNERS, 0.0, math.inf, body="body")
    with pytest.raises(InputError, match="a cutting path, not a body in contact"):
        sim.add_cut(lambda t: CORNERS, 0.0, 1.0, body="body", contact=True)


def test_a_scene_cuts_with_an_obstacles_blade(tmp_path):
    from tissuesim.errors import SceneError
    from tissuesim.scene.loader import build_scene

    data = {
        "simulation": {"integrator": "quasistatic", "time_step": 0.25},
        "bodies": [{"name": "block", "mesh": {"generator": "box", "lower": [0, 0, 0],
                    "upper": [0.1, 0.04, 0.04], "divisions": [10, 4, 4]},
                    "material": {"model": "neo_hookean", "youngs_modulus": 3e3,
                                 "poisson_ratio": 0.4},
                    "fix": {"on_plane": {"axis": 2, "value": 0.0}}}],
        "contact": {"dhat": 1e-4},
        "obstacles": [{"name": "scalpel", "file": "scalpel.obj",
                       "translation": ["0.2 * t", 0, 0]}],
        "cuts": [{"obstacle": "scalpel", "body": "block", "name": "incision"}],
    }  # fmt: skip
    lines = [f"v {x} {y} {z}" for x, y, z in CORNERS] + ["f 1 2 3"]
    (tmp_path / "scalpel.obj").write_text("\n".join(lines) + "\n")
    data["cuts"][0]["contact"] = False  # it passes through the block: cut after each step
    sim = build_scene(data, base_dir=tmp_path, source="s.toml").simulation
    for _ in range(4):
        record = sim.step()
    assert record.extra["cuts"]["incision"]["area_m2"] == pytest.approx(0.1 * 0.015, rel=1e-9)
    del data["cuts"][0]["contact"]  # in contact with it (the default): the cut goes first
    sim = build_scene(data, base_dir=tmp_path, source="s.toml").simulation
    table = sim.system.contact.table
    assert table.enabled[table.names.index("block"), table.names.index("scalpel")]
    for _ in range(4):
        record = sim.step()
        assert not sim.system.contact.intersecting(sim.state.x)
    area = record.extra["cuts"]["incision"]["area_m2"]
    assert 0.1 * 0.015 < area <= 0.1 * (0.015 + 0.01) + 1e-12  # a cell (10 mm) deeper at most
    data["cuts"][0]["contact"] = "yes"
    with pytest.raises(SceneError, match=r"cuts\[1\]: contact must be true"):
        build_scene(data, base_dir=tmp_path, source="s.toml")
    data["cuts"][0]["contact"] = False
    data["cuts"][0]["blade"] = [[0, 0, 0], [1, 0, 0]]
    with pytest.raises(SceneError, match=r"cuts\[1\]: give blade = \[...\] or obstacle"):
        build_scene(data, base_dir=tmp_path, source="s.toml")
