"""A FEM body that tears (bodies/organ_tear.py): a strip pulled until it tears parts at the load
its strength predicts (within one load increment) and carries nothing after; the crack is
normal to the pull, through the whole section, and no gram is lost."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import tissuesim as ts
from tissuesim.errors import InputError

E, NU, STRENGTH = 1e4, 0.3, 3000.0  # Pa
L, W, H = 0.1, 0.02, 0.01
STEP = 0.0005  # m of pull per step


def strip(divisions: int, rate: float = 1.0) -> ts.Simulation:
    """Pulled along x with rollers at both ends (free to narrow): a uniform uniaxial stress;
    the far end moves ``rate`` STEP per step."""
    mesh = ts.box((0, 0, 0), (L, W, H), (divisions, max(divisions // 5, 2), 2))
    material = ts.make_material("neo_hookean", youngs_modulus=E, poisson_ratio=NU)
    sim = ts.Simulation(mesh, material, density=1000.0, integrator="quasistatic", time_step=1.0)
    P = mesh.points
    sim.add_dirichlet(np.flatnonzero(P[:, 0] < 1e-9), None, (0,), name="left")
    pull = lambda X, t: np.column_stack([rate * STEP * t + 0 * X[:, 0], 0 * X[:, 0], 0 * X[:, 0]])  # noqa: E731
    sim.add_dirichlet(np.flatnonzero(P[:, 0] > L - 1e-9), pull, (0,), name="right")
    for x0, name in ((0.0, "a"), (L, "b")):  # no rigid motion of either piece
        end = np.abs(P[:, 0] - x0) < 1e-9
        sim.add_dirichlet(np.flatnonzero(end & (P[:, 1] < 1e-9) & (P[:, 2] < 1e-9)), None,
                          (1, 2), name=f"pin{name}")  # fmt: skip
        sim.add_dirichlet(np.flatnonzero(end & (P[:, 1] > W - 1e-9) & (P[:, 2] < 1e-9)), None,
                          (2,), name=f"pinz{name}")  # fmt: skip
    return sim


def predicted_force() -> float:
    """The pull at which the uniaxial Cauchy stress of the compressible neo-Hookean law reaches
    the strength: lateral stretch l2 from P_22 = mu l2 + (lam ln J - mu) / l2 = 0, J = l1 l2^2,
    sigma_11 = P_11 l1 / J, P_11 = mu l1 + (lam ln J - mu) / l1; the force is P_11 W H."""
    mu, lam = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))

    def lateral(l1):
        return brentq(lambda l2: mu * l2**2 + lam * np.log(l1 * l2**2) - mu, 0.3, 1.0)

    def nominal(l1):
        J = l1 * lateral(l1) ** 2
        return mu * l1 + (lam * np.log(J) - mu) / l1

    l1 = brentq(lambda l1: nominal(l1) * l1 / (l1 * lateral(l1) ** 2) - STRENGTH, 1.0, 2.0)
    return nominal(l1) * W * H


@pytest.mark.parametrize("divisions", [10, 20])
def test_a_pulled_strip_tears_at_its_strength_and_then_carries_nothing(divisions):
    sim = strip(divisions)
    sim.set_tearing(body="body", stress=STRENGTH)
    mass = sim.model.mass.lumped.sum()
    forces, torn = [], None
    for k in range(80):
        record = sim.step()
        forces.append(record.extra["forces"]["right"][0])
        tear = record.extra["cuts"]["body.tear"]
        assert tear["mass_kg"] == pytest.approx(mass / 3, rel=1e-12)  # reported every step
        if tear["pieces"] == 2:
            torn = k
            break
    assert torn is not None
    F = predicted_force()
    assert forces[torn - 1] < F <= forces[torn]  # within the step's load increment
    assert tear["area_m2"] == pytest.approx(W * H, rel=1e-9)  # through the whole section
    after = sim.step().extra
    assert after["cuts"]["body.tear"]["pieces"] == 2  # reported after it has stopped too
    assert abs(after["forces"]["right"][0]) < 1e-6 * F  # parted: the pull carries nothing
    assert sim.model.mass.lumped.sum() == pytest.approx(mass, rel=1e-12)
    normal = sim.organ_tears[0].cracks[0].normal
    assert abs(normal[0]) == pytest.approx(1.0, abs=1e-9)  # the crack is normal to the pull


def test_tearing_refuses_what_it_cannot_mean():
    sim = strip(10)
    with pytest.raises(InputError, match="one of the two"):
        sim.set_tearing(body="body", stress=1e3, stretch=1.2)
    with pytest.raises(InputError, match="stretch must be > 1"):
        sim.set_tearing(body="body", stretch=0.9)
    with pytest.raises(InputError, match="not at a strain threshold"):
        sim.set_tearing(0.5, body="body")


def test_the_shipped_strip_tears_at_its_held_end_and_the_grasper_force_drops_to_zero():
    from tissuesim.cli import example_path
    from tissuesim.scene.loader import load_scene

    sim = load_scene(example_path("strip_tearing")).simulation
    forces, pieces = [], []
    for _ in range(64):
        record = sim.step()
        forces.append(record.extra["forces"]["grasper"][0])
        pieces.append(record.extra["cuts"]["strip.tear"].get("pieces", 1))
    peak = int(np.argmax(forces))
    assert 0.4 < forces[peak] < 0.6 and 2 in pieces  # it tore
    assert max(np.diff(forces[:peak])) > 0 and min(np.diff(forces[: peak + 1])) > 0  # rising
    assert abs(forces[-1]) < 1e-6 * forces[peak]  # parted: nothing pulls back
    assert sim.organ_tears[0].cracks[0].point[0] < 0.01  # where the clamp stiffens it: the held end


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ({"body": "liver", "stress": 1e3}, "'liver' is not a body of this scene"),
        ({"body": "strip", "threshold": 0.5}, "not at a strain threshold"),
        ({"body": "strip", "stress": -1.0}, "must be a stress > 0"),
        ({"body": "strip"}, "one of the two"),
        ({"stress": 1e3}, "for a body that tears"),
    ],
)
def test_scene_tearing_of_a_body_errors_name_the_key(table, message):
    import tomllib

    from tissuesim.cli import example_path
    from tissuesim.errors import SceneError
    from tissuesim.scene.loader import build_scene

    data = tomllib.loads(example_path("strip_tearing").read_text())
    data["tearing"] = table
    with pytest.raises(SceneError, match=message) as error:
        build_scene(data)
    assert "[tearing]" in str(error.value) and "\n" not in str(error.value)
