"""FEBio's generalised-alpha dynamics (<solver> rhoi, alpha, beta, gamma; febio/reader.py ->
time/integrators/generalized_alpha.py): each rhoi read as FEBio's FESolidSolver2::Init sets the
scheme up, and a model of our own (a rigid block on a rail, pulled by a rigid force against a
rigid spring: a mass-spring) against the closed-form recurrence of FEBio's equations; the
refusals in one line."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from tissuesim.errors import TissueSimError
from tissuesim.febio import load_febio, read_feb
from tissuesim.time.integrators.generalized_alpha import febio_weights

K, F, H, STEPS = 40.0, 6.0, 0.05, 24  # N/m, N, s; the block's mass is 1 kg


def _cube(first: int, lower: tuple[float, float, float]) -> tuple[str, str]:
    x0, y0, z0 = lower
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
               (0, 1, 1)]  # fmt: skip
    nodes = "".join(
        f'      <node id="{first + k}">{x0 + a:g},{y0 + b:g},{z0 + c:g}</node>\n'
        for k, (a, b, c) in enumerate(corners)
    )
    return nodes, ",".join(str(first + k) for k in range(8))


def deck(solver: str) -> str:
    """A fixed rigid ground and a 1 kg rigid block on a prismatic joint along x, held by a
    40 N/m rigid spring at its rest length and pulled by 6 N from t = 0, DYNAMIC."""
    ground_nodes, ground = _cube(1, (-0.5, -0.5, -1.0))
    block_nodes, block = _cube(9, (1.0, -0.5, -0.5))
    fixed = "".join(f"      <R{d}_dof>1</R{d}_dof>\n" for d in "xyzuvw")
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>DYNAMIC</analysis>
    <time_steps>{STEPS}</time_steps>
    <step_size>{H}</step_size>
    <solver type="solid">
{solver}    </solver>
  </Control>
  <Material>
    <material id="1" name="ground" type="rigid body"><density>1</density></material>
    <material id="2" name="block" type="rigid body"><density>1</density></material>
  </Material>
  <Mesh>
    <Nodes name="all">
{ground_nodes}{block_nodes}    </Nodes>
    <Elements type="hex8" name="g"><elem id="1">{ground}</elem></Elements>
    <Elements type="hex8" name="b"><elem id="2">{block}</elem></Elements>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="g" mat="ground"/>
    <SolidDomain name="b" mat="block"/>
  </MeshDomains>
  <Rigid>
    <rigid_bc name="fix" type="rigid_fixed">
      <rb>ground</rb>
{fixed}    </rigid_bc>
    <rigid_connector name="rail" type="rigid prismatic joint">
      <body_a>ground</body_a>
      <body_b>block</body_b>
      <joint_origin>1.5,0,0</joint_origin>
      <translation_axis>1,0,0</translation_axis>
      <transverse_axis>0,1,0</transverse_axis>
      <prescribed_translation>0</prescribed_translation>
      <translation>0</translation>
      <force>0</force>
    </rigid_connector>
    <rigid_connector name="spring" type="rigid spring">
      <body_a>ground</body_a>
      <body_b>block</body_b>
      <k>{K:g}</k>
      <insertion_a>0,0,0</insertion_a>
      <insertion_b>1.5,0,0</insertion_b>
    </rigid_connector>
    <rigid_load name="pull" type="rigid_force">
      <rb>block</rb>
      <dof>Rx</dof>
      <value lc="1">{F:g}</value>
    </rigid_load>
  </Rigid>
  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points><pt>0,1</pt><pt>10,1</pt></points>
    </load_controller>
  </LoadData>
</febio_spec>
"""


def _solver(**values: float) -> str:
    return "".join(f"      <{k}>{v:g}</{k}>\n" for k, v in values.items())


def _load(text: str, tmp_path: Path):
    path = tmp_path / "m.feb"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_febio(path)


@pytest.mark.parametrize(
    "values, integrator, scheme",
    [
        ({"rhoi": 0.5}, "generalized_alpha", febio_weights(0.5)),
        ({"rhoi": 0.0, "beta": 0.3}, "generalized_alpha", (1.0, 2.0, 1.0, 1.5)),
        ({"rhoi": 1.0}, "generalized_alpha", (0.5, 0.5, 0.25, 0.5)),
        ({"rhoi": -1.0, "beta": 0.3, "gamma": 0.6}, "newmark", (0.25, 0.5)),
        ({"beta": 0.3, "gamma": 0.6}, "newmark", (0.3, 0.6)),
        ({"alpha": 0.8, "beta": 0.3, "gamma": 0.6}, "generalized_alpha", (0.8, 0.8, 0.3, 0.6)),
        ({"rhoi": 2.0, "alpha": 0.9}, "generalized_alpha", (0.9, 0.9, 0.25, 0.5)),
    ],
)
def test_each_rhoi_sets_the_scheme_febio_sets_up(values, integrator, scheme, tmp_path):
    """rhoi in [0, 1]: FEBio's weights from rhoi (its beta and gamma ignored); -1: the
    trapezoidal rule; any other rhoi: beta and gamma as given, with alpha_f = alpha_m = alpha
    (alpha = 1: Newmark's method)."""
    sim = _load(deck(_solver(**values)), tmp_path).simulation
    assert sim.integrator == integrator
    got = sim.generalized_alpha if integrator == "generalized_alpha" else sim.newmark
    assert got == pytest.approx(scheme, abs=1e-15)


def _recurrence(rho: float, steps: int) -> np.ndarray:
    """The block's displacement by FEBio's equations (the rigid body's inertia with alpha_m,
    ``FERigidSolverNew::InertialForces``; the spring at x_{n+alpha_f}, ``FERigidSpring``),
    m = 1: alpha_m a1 + (1 - alpha_m) a0 + k (alpha_f x1 + (1 - alpha_f) x0) = f with
    Newmark's updates, from a_0 = f."""
    af, am, beta, gamma = febio_weights(rho)
    x, v, a, out = 0.0, 0.0, F, []
    for _ in range(steps):
        # x1 = x + H v + H^2 ((1/2 - beta) a + beta a1) in the equation for a1
        pred = x + H * v + H * H * (0.5 - beta) * a
        a1 = (F - (1 - am) * a - K * (af * pred + (1 - af) * x)) / (am + af * K * beta * H * H)
        x1 = pred + beta * H * H * a1
        v += H * ((1 - gamma) * a + gamma * a1)
        x, a = x1, a1
        out.append(x)
    return np.array(out)


@pytest.mark.parametrize("rho", [0.0, 0.5, 1.0])
def test_a_rigid_mass_spring_follows_febios_recurrence(rho, tmp_path):
    """omega h = 0.32: the block's place step by step is the recurrence's to 1e-7 of the
    static displacement F / k (the joints' augmented Lagrangian tolerance aside)."""
    sim = _load(deck(_solver(rhoi=rho)), tmp_path).simulation
    got = []
    for _ in range(STEPS):
        sim.step()
        got.append(sim.rigid_state("block")[0][0] - 1.5)
    expected = _recurrence(rho, STEPS)
    assert np.max(np.abs(np.array(got) - expected)) < 1e-7 * F / K
    # and the motion is a vibration about F / k of amplitude about F / k
    assert np.max(got) > 1.5 * F / K


def test_a_bad_alpha_is_refused_on_its_line(tmp_path):
    path = tmp_path / "bad.feb"
    path.write_text(deck(_solver(alpha=0.3)))
    with pytest.raises(TissueSimError, match="alpha_f") as info:
        read_feb(path)
    assert "bad.feb:" in str(info.value) and "<alpha>" in str(info.value)
    assert "\n" not in str(info.value)
