"""FEBio's porous neo-Hookean and Shenoy read from decks of our own: a cube pressed evenly on
three faces to s = 0.8 (a dilation s I), its wall force against FEBio's Cauchy stress by hand;
a Shenoy cube pulled along x, its pull the law's stress with the lateral stresses zero."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.febio import load_febio

FACE = """    <bc name="{name}" node_set="{nodes}" type="prescribed displacement">
      <dof>{dof}</dof><value lc="1">-0.2</value><relative>0</relative>
    </bc>"""

DECK = """<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>2</time_steps>
    <step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="tissue" type="porous neo-Hookean">
      <E>3000</E><phi0>0.3</phi0>
    </material>
  </Material>
  <Mesh>
    <Nodes name="cube">
      <node id="1">0,0,0</node>
      <node id="2">1,0,0</node>
      <node id="3">1,1,0</node>
      <node id="4">0,1,0</node>
      <node id="5">0,0,1</node>
      <node id="6">1,0,1</node>
      <node id="7">1,1,1</node>
      <node id="8">0,1,1</node>
    </Nodes>
    <Elements type="hex8" name="cube">
      <elem id="1">1,2,3,4,5,6,7,8</elem>
    </Elements>
    <NodeSet name="x0">1,4,5,8</NodeSet>
    <NodeSet name="y0">1,2,5,6</NodeSet>
    <NodeSet name="z0">1,2,3,4</NodeSet>
    <NodeSet name="x1">2,3,6,7</NodeSet>
    <NodeSet name="y1">3,4,7,8</NodeSet>
    <NodeSet name="z1">5,6,7,8</NodeSet>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="cube" mat="tissue"/>
  </MeshDomains>
  <Boundary>
    <bc name="sx" node_set="x0" type="zero displacement">
      <x_dof>1</x_dof><y_dof>0</y_dof><z_dof>0</z_dof>
    </bc>
    <bc name="sy" node_set="y0" type="zero displacement">
      <x_dof>0</x_dof><y_dof>1</y_dof><z_dof>0</z_dof>
    </bc>
    <bc name="sz" node_set="z0" type="zero displacement">
      <x_dof>0</x_dof><y_dof>0</y_dof><z_dof>1</z_dof>
    </bc>
{faces}
  </Boundary>
  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points><pt>0,0</pt><pt>1,1</pt></points>
    </load_controller>
  </LoadData>
</febio_spec>
"""


def test_pressed_cube_wall_force_is_febios_stress(tmp_path):
    """s = 0.8: sigma = mu/J R b + (mu/J (phi0 R I1/3 - J)) / (J - phi0) I (FEBio's Stress),
    R = (J_bar/J)^(2/3), mu = E/3 (1 + (1 - phi0)^2/2); the force on a face sigma s^2."""
    faces = "\n".join(FACE.format(name=f"p{a}", nodes=f"{a}1", dof=a) for a in ("x", "y", "z"))
    path = tmp_path / "porous.feb"
    path.write_text(DECK.format(faces=faces))
    sim = load_febio(path).simulation
    sim.step()
    forces = sim.step().extra["forces"]
    E, phi, s = 3000.0, 0.3, 0.8
    mu, J = E / 3 * (1 + 0.5 * (1 - phi) ** 2), s**3
    R = ((J - phi) / (1 - phi) / J) ** (2 / 3)
    sigma = mu / J * R * s * s + mu / J * (phi * R * 3 * s * s / 3 - J) / (J - phi)
    assert sigma < 0.0
    for a, k in (("x", 0), ("y", 1), ("z", 2)):
        assert forces[f"p{a}"][k] == pytest.approx(sigma * s * s, rel=1e-7)
    np.testing.assert_allclose(sim.body_positions("body"), 0.8 * sim.body("body").mesh.points,
                               atol=1e-12)  # fmt: skip


def test_shenoy_cube_pulled_is_the_laws_stress(tmp_path):
    """FEBio's Shenoy (matrix + fibres on the principal stretches), a cube pulled 15 % along x,
    free across: its lateral stresses vanish and the pull is P_xx of the law at the stretches
    (the law itself checked against finite differences and FEBio's Cauchy stress elsewhere)."""
    from tissuesim.materials import make_material

    params = dict(mu=770.0, k=1670.0, Ef=13460.0, lam_c=1.02, lam_t=0.255, n=5, m=3)
    shenoy = "".join(f"<{k}>{v}</{k}>" for k, v in params.items())
    pull = FACE.format(name="px", nodes="x1", dof="x").replace("-0.2", "0.15")
    text = DECK.format(faces=pull).replace('type="porous neo-Hookean"', 'type="Shenoy"')
    path = tmp_path / "shenoy.feb"
    path.write_text(text.replace("<E>3000</E><phi0>0.3</phi0>", shenoy))
    sim = load_febio(path).simulation
    sim.step()
    forces = sim.step().extra["forces"]
    X, x = sim.body("body").mesh.points, sim.body_positions("body")
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    P = make_material("Shenoy", **params).stress(np.diag(stretch)[None])[0]
    assert stretch[0] == pytest.approx(1.15)
    np.testing.assert_allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert forces["px"][0] == pytest.approx(P[0, 0], rel=1e-6)


def test_muscle_cube_pulled_along_its_fibre_is_the_laws_stress(tmp_path):
    """FEBio's muscle material (uncoupled: hex8 with the three-field element, tissuesim's mean
    dilatation), a cube pulled 15 % along its fibre x, free across: the lateral stresses vanish
    and the pull is P_xx of the law at the stretches (the law itself checked against finite
    differences and FEBio's DevStress elsewhere)."""
    from tissuesim.febio import febio_scene, read_feb
    from tissuesim.materials import make_material

    params = dict(g1=500.0, g2=500.0, g3=0.0, p1=0.05, p2=6.6, Lofl=1.05, smax=3e4,
                  lam_max=1.4, activation=0.2, k=1e5)  # fmt: skip
    muscle = "".join(f"<{k}>{v}</{k}>" for k, v in params.items())
    muscle += '<fiber type="vector">1,0,0</fiber>'
    pull = FACE.format(name="px", nodes="x1", dof="x").replace("-0.2", "0.15")
    text = DECK.format(faces=pull).replace('type="porous neo-Hookean"', 'type="muscle material"')
    path = tmp_path / "muscle.feb"
    path.write_text(text.replace("<E>3000</E><phi0>0.3</phi0>", muscle))
    data, _ = febio_scene(read_feb(path), "x")
    assert data["simulation"]["formulation"] == "mean_dilatation"
    sim = load_febio(path).simulation
    sim.step()
    forces = sim.step().extra["forces"]
    X, x = sim.body("body").mesh.points, sim.body_positions("body")
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    P = make_material("muscle material", **params).stress(np.diag(stretch)[None])[0]
    assert stretch[0] == pytest.approx(1.15)
    np.testing.assert_allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert forces["px"][0] == pytest.approx(P[0, 0], rel=1e-6)
