"""FEBio's multigeneration read from a deck of our own: a cube stretched along x to 1.2 (held
across) by t = 0.5 and brought back to its rest shape by t = 1; a second neo-Hookean generation
is born at t = 0.6 with the stretched shape as its reference, so that at the end the cube is
at rest but pulled back on by it: the wall force is the neo-Hookean P_xx at 1/1.2."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.febio import FebError, load_febio, read_feb

DECK = """<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>10</time_steps>
    <step_size>0.1</step_size>
  </Control>
  <Material>
    <material id="1" name="tissue" type="multigeneration">
      <generation>
        <start_time>0</start_time>
        <solid type="neo-Hookean"><E>1000</E><v>0.3</v></solid>
      </generation>
      <generation>
        <start_time>{born}</start_time>
        <solid type="neo-Hookean"><E>1000</E><v>0.3</v></solid>
      </generation>
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
    <NodeSet name="x1">2,3,6,7</NodeSet>
    <NodeSet name="all">1,2,3,4,5,6,7,8</NodeSet>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="cube" mat="tissue"/>
  </MeshDomains>
  <Boundary>
    <bc name="sx" node_set="x0" type="zero displacement">
      <x_dof>1</x_dof><y_dof>0</y_dof><z_dof>0</z_dof>
    </bc>
    <bc name="across" node_set="all" type="zero displacement">
      <x_dof>0</x_dof><y_dof>1</y_dof><z_dof>1</z_dof>
    </bc>
    <bc name="pull" node_set="x1" type="prescribed displacement">
      <dof>x</dof><value lc="1">0.2</value><relative>0</relative>
    </bc>
  </Boundary>
  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points><pt>0,0</pt><pt>0.5,1</pt><pt>1,0</pt></points>
    </load_controller>
  </LoadData>
</febio_spec>
"""


def test_a_generation_born_stretched_pulls_back_at_rest(tmp_path):
    E, nu = 1000.0, 0.3
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))

    def pxx(s: float) -> float:  # neo-Hookean, F = diag(s, 1, 1)
        return mu * (s - 1 / s) + lam * np.log(s) / s

    path = tmp_path / "mg.feb"
    path.write_text(DECK.format(born=0.6))
    sim = load_febio(path).simulation
    forces = [sim.step().extra["forces"]["pull"][0] for _ in range(10)]
    # t = 0.5: one generation at 1.2; t = 0.6 (born with F(0.5) = 1.2): both at 1.16
    assert forces[4] == pytest.approx(pxx(1.2), rel=1e-7)
    assert forces[5] == pytest.approx(pxx(1.16) + pxx(1.16 / 1.2), rel=1e-7)
    assert forces[9] == pytest.approx(pxx(1 / 1.2), rel=1e-7)  # at rest, pulled back
    assert forces[9] < 0.0


def test_refusals(tmp_path):
    path = tmp_path / "mg.feb"
    path.write_text(DECK.format(born=0.0))
    with pytest.raises(FebError, match=r"mg.feb:\d+ <material>: .*start times increase"):
        read_feb(path)
    path.write_text(DECK.format(born=0.6).replace("<start_time>0</start_time>", "<t>0</t>"))
    with pytest.raises(FebError, match=r"mg.feb:\d+ <generation>: .*<start_time> and <solid>"):
        read_feb(path)
