"""FEBio's cubic and orthotropic CLE read from a deck of our own: a cube pulled along x, free
across, against the closed form (tension along x, compression across: the diagonal moduli
switch), and the orthotropic law's axes from mat_axis."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.febio import febio_scene, load_febio, read_feb
from tissuesim.materials import make_material

DECK = """<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>2</time_steps>
    <step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="tissue" type="{kind}">
{params}
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
    <bc name="pull" node_set="x1" type="prescribed displacement">
      <dof>x</dof><value lc="1">0.1</value><relative>0</relative>
    </bc>
  </Boundary>
  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points><pt>0,0</pt><pt>1,1</pt></points>
    </load_controller>
  </LoadData>
</febio_spec>
"""
CUBIC = "      <lp1>1000</lp1><lm1>200</lm1><l2>100</l2><mu>200</mu>"


def test_cubic_cle_pulled_against_the_closed_form(tmp_path):
    """l = 1.1 along x: E11 = (l^2 - 1)/2 > 0 (lp1), E22 = E33 < 0 (lm1) from S22 = 0,
    (mu + lm1 + l2) E22 + l2 E11 = 0; the pull P11 = l ((mu + lp1) E11 + 2 l2 E22)."""
    lp1, lm1, l2, mu = 1000.0, 200.0, 100.0, 200.0
    path = tmp_path / "cle.feb"
    path.write_text(DECK.format(kind="cubic CLE", params=CUBIC))
    sim = load_febio(path).simulation
    sim.step()
    forces = sim.step().extra["forces"]
    X, x = sim.body("body").mesh.points, sim.body_positions("body")
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    l = 1.1
    E11 = (l * l - 1) / 2
    E22 = -l2 * E11 / (mu + lm1 + l2)
    t = np.sqrt(1 + 2 * E22)
    np.testing.assert_allclose(stretch, [l, t, t], rtol=1e-8)
    assert forces["pull"][0] == pytest.approx(l * ((mu + lp1) * E11 + 2 * l2 * E22), rel=1e-6)


def test_orthotropic_cle_reads_its_moduli_and_axes(tmp_path):
    params = ("      <lp11>2</lp11><lm11>0.2</lm11><lp22>1</lp22><lm22>0.1</lm22>"
              "<lp33>1</lp33><lm33>0.1</lm33><l12>0.1</l12><l23>0.1</l23><l31>0.1</l31>"
              "<mu1>0.2</mu1><mu2>0.1</mu2><mu3>0.1</mu3>\n"
              '      <mat_axis type="vector"><a>0,1,0</a><d>-1,0,0</d></mat_axis>')  # fmt: skip
    path = tmp_path / "cle.feb"
    path.write_text(DECK.format(kind="orthotropic CLE", params=params))
    data, _ = febio_scene(read_feb(path), "x")
    material = data["material"]
    assert material["model"] == "orthotropic CLE"  # FEBio's name, a registered spelling
    assert material["lp11"] == 2.0 and material["mu3"] == 0.1
    np.testing.assert_allclose(material["mat_axis_a"], [0, 1, 0])
    np.testing.assert_allclose(material["mat_axis_d"], [-1, 0, 0])


def test_st_venant_kirchhoff_is_stvk_alone_and_in_a_mixture(tmp_path):
    """FEBio's St.Venant-Kirchhoff (FEStVenantKirchhoff, the stress of isotropic elastic)."""
    path = tmp_path / "svk.feb"
    path.write_text(DECK.format(kind="St.Venant-Kirchhoff", params="      <E>1000</E><v>0.3</v>"))
    data, _ = febio_scene(read_feb(path), "x")
    assert data["material"] == {"model": "stvk", "youngs_modulus": 1000.0, "poisson_ratio": 0.3}
    mixture = ('      <solid type="St.Venant-Kirchhoff"><E>1000</E><v>0.3</v></solid>\n'
               '      <solid type="neo-Hookean"><E>500</E><v>0.2</v></solid>')  # fmt: skip
    path.write_text(DECK.format(kind="solid mixture", params=mixture))
    data, _ = febio_scene(read_feb(path), "x")
    assert data["material"]["components"][0]["model"] == "stvk"
    sim = load_febio(path).simulation
    sim.step()
    forces = sim.step().extra["forces"]
    X, x = sim.body("body").mesh.points, sim.body_positions("body")
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    law = make_material("solid_mixture", components=[
        {"model": "stvk", "youngs_modulus": 1000.0, "poisson_ratio": 0.3},
        {"model": "neo_hookean", "youngs_modulus": 500.0, "poisson_ratio": 0.2},
    ])  # fmt: skip
    P = law.stress(np.diag(stretch)[None])[0]
    np.testing.assert_allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert forces["pull"][0] == pytest.approx(P[0, 0], rel=1e-6)
