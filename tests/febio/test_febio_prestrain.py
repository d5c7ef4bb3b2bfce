"""FEBio's prestrain elastic read from decks of our own: two hex8 elements in a row along x on
their symmetry planes, each with its own prestrain from a <MeshData> map, released: each
element comes to Fp^-1, so the nodes' x follow by hand (a prestrain gradient F0 = diag(a, 1, 1)
per element; an in-situ stretch along the fibre x, isochoric); the refusals name the element and
its line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tissuesim.febio import FebError, load_febio, read_feb

DECK = """<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>1</time_steps>
    <step_size>1</step_size>
  </Control>
  <Material>
    <material id="1" name="tissue" type="prestrain elastic">
      <elastic type="coupled trans-iso Mooney-Rivlin">
        <c1>1000</c1><c2>100</c2><c3>50</c3><c4>5</c4><c5>2000</c5><lam_max>1.1</lam_max>
        <k>20000</k>
        <fiber type="vector">1,0,0</fiber>
      </elastic>
{prestrain}
    </material>
  </Material>
  <Mesh>
    <Nodes name="bar">
      <node id="1">0,0,0</node>
      <node id="2">1,0,0</node>
      <node id="3">1,1,0</node>
      <node id="4">0,1,0</node>
      <node id="5">0,0,1</node>
      <node id="6">1,0,1</node>
      <node id="7">1,1,1</node>
      <node id="8">0,1,1</node>
      <node id="9">2,0,0</node>
      <node id="10">2,1,0</node>
      <node id="11">2,0,1</node>
      <node id="12">2,1,1</node>
    </Nodes>
    <Elements type="hex8" name="bar">
      <elem id="1">1,2,3,4,5,6,7,8</elem>
      <elem id="2">2,9,10,3,6,11,12,7</elem>
    </Elements>
    <NodeSet name="x0">1,4,5,8</NodeSet>
    <NodeSet name="y0">1,2,5,6,9,11</NodeSet>
    <NodeSet name="z0">1,2,3,4,9,10</NodeSet>
  </Mesh>
  <MeshDomains>
    <SolidDomain name="bar" mat="tissue"/>
  </MeshDomains>
  <MeshData>
{data}
  </MeshData>
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
  </Boundary>
</febio_spec>
"""

GRADIENT = """      <prestrain type="prestrain gradient">
        <ramp>1</ramp>
        <F0 type="map">F0_map</F0>
      </prestrain>"""
F0_DATA = """    <ElementData name="F0_map" elem_set="bar" data_type="mat3">
      <e lid="1">1.1,0,0,0,1,0,0,0,1</e>
      <e lid="2">0.9,0,0,0,1,0,0,0,1</e>
    </ElementData>"""
IN_SITU = """      <prestrain type="in-situ stretch">
        <stretch type="map">pre_stretch</stretch>
        <isochoric>1</isochoric>
      </prestrain>"""
STRETCH_DATA = """    <ElementData name="pre_stretch" elem_set="bar">
      <e lid="1">1.05</e>
      <e lid="2">1.05</e>
    </ElementData>"""


def _deck(tmp_path: Path, prestrain: str, data: str) -> Path:
    path = tmp_path / "prestrain.feb"
    path.write_text(DECK.format(prestrain=prestrain, data=data))
    return path


def _released(path: Path) -> tuple[np.ndarray, np.ndarray]:
    sim = load_febio(path).simulation
    sim.step()
    return sim.body("body").mesh.points, sim.body_positions("body")


def test_each_element_comes_to_its_inverse_prestrain(tmp_path):
    """F0 = diag(1.1, 1, 1) and diag(0.9, 1, 1): the elements' lengths 1/1.1 and 1/0.9."""
    X, x = _released(_deck(tmp_path, GRADIENT, F0_DATA))
    want = np.where(X[:, 0] == 0, 0.0, np.where(X[:, 0] == 1, 1 / 1.1, 1 / 1.1 + 1 / 0.9))
    np.testing.assert_allclose(x[:, 0], want, atol=1e-8)
    np.testing.assert_allclose(x[:, 1:], X[:, 1:], atol=1e-8)


def test_in_situ_stretch_along_the_fibre(tmp_path):
    """lam = 1.05 along x, isochoric: Fp = diag(lam, lam^-1/2, lam^-1/2), released to Fp^-1."""
    X, x = _released(_deck(tmp_path, IN_SITU, STRETCH_DATA))
    lam = 1.05
    np.testing.assert_allclose(x, X * [1 / lam, np.sqrt(lam), np.sqrt(lam)], atol=1e-8)


def test_refusals(tmp_path):
    with pytest.raises(FebError, match=r"prestrain.feb:\d+ <F0>: map 'F0_map': no <ElementData"):
        load_febio(_deck(tmp_path, GRADIENT, ""))
    short = F0_DATA.replace('      <e lid="2">0.9,0,0,0,1,0,0,0,1</e>\n', "")
    with pytest.raises(FebError, match=r"prestrain.feb:\d+ <ElementData>: .*element 2 of part"):
        load_febio(_deck(tmp_path, GRADIENT, short))
    with pytest.raises(FebError, match=r"prestrain.feb:\d+ <ElementData>: data_type 'mat3ds'"):
        read_feb(_deck(tmp_path, GRADIENT, F0_DATA.replace('"mat3"', '"mat3ds"')))
    bad = GRADIENT.replace("prestrain gradient", "prestrain twist")
    with pytest.raises(FebError, match=r"prestrain.feb:\d+ <prestrain>: prestrain type"):
        read_feb(_deck(tmp_path, bad, F0_DATA))
    bad = GRADIENT.replace("<ramp>1</ramp>", '<ramp lc="1">1</ramp>')
    with pytest.raises(FebError, match=r"prestrain.feb:\d+ <ramp>: .*curve"):
        read_feb(_deck(tmp_path, bad, F0_DATA))
