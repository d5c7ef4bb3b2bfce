"""FEBio's kinematic growth read from decks of our own: a cube on its symmetry planes grows
free of stress (volume growth g: stretch g; fiber growth along the angles direction z: stretch
g along z only; general growth), and a fibre growth held between two walls, whose stretches and
wall force follow the closed form; the refusals name the element and its line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuesim.febio import FebError, load_febio, read_feb

DECK = """<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>2</time_steps>
    <step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="tissue" type="kinematic growth">
      <elastic type="neo-Hookean"><E>10000</E><v>0.3</v></elastic>
{growth}
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
{wall}
  </Boundary>
  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points><pt>0,1</pt><pt>1,1.4</pt></points>
    </load_controller>
  </LoadData>
</febio_spec>
"""

WALL = """    <bc name="wall" node_set="x1" type="prescribed displacement">
      <dof>x</dof><value>0</value><relative>0</relative>
    </bc>"""


def _deck(tmp_path: Path, growth: str, wall: str = "") -> Path:
    path = tmp_path / "growth.feb"
    path.write_text(DECK.format(growth=growth, wall=wall))
    return path


def _run(path: Path) -> list[tuple[np.ndarray, dict]]:
    """The cube's stretches (x, y, z) and the forces after each step (t = 0.5, 1)."""
    sim = load_febio(path).simulation
    out = []
    for _ in range(2):
        forces = sim.step().extra["forces"]
        X, x = sim.body("body").mesh.points, sim.body_positions("body")
        out.append((np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)]), forces))
    return out


@pytest.mark.parametrize(
    ("growth", "expected"),
    [
        ('<growth type="volume growth"><multiplier lc="1">1</multiplier></growth>',
         lambda g: [g, g, g]),
        ('<growth type="fiber growth"><multiplier lc="1">1</multiplier>'
         '<fiber type="angles"><theta>0</theta><phi>0</phi></fiber></growth>',
         lambda g: [1.0, 1.0, g]),
        ('<growth type="area growth"><multiplier lc="1">1</multiplier>'
         '<fiber type="vector">0,1,0</fiber></growth>',
         lambda g: [np.sqrt(g), 1.0, np.sqrt(g)]),
        ('<growth type="general growth"><iso lc="1">1</iso><ani>1.2</ani>'
         "<fiber>1,0,0</fiber></growth>",
         lambda g: [g + 0.2, g, g]),
    ],
    ids=["volume", "fiber", "area", "general"],
)  # fmt: skip
def test_free_growth_is_the_growth_tensor(tmp_path, growth, expected):
    """Free on three faces: the body takes Fg (the multiplier 1 -> 1.4 over t = 0..1)."""
    for (stretch, _), g in zip(_run(_deck(tmp_path, growth)), (1.2, 1.4), strict=True):
        np.testing.assert_allclose(stretch, expected(g), rtol=1e-7)


def test_fibre_growth_between_walls_pushes_on_them(tmp_path):
    """Fiber growth g along x, the cube held at x = 0 and x = 1: Fe = diag(1/g, t, t) with the
    neo-Hookean's lateral stress zero, mu (t^2 - 1) + lam ln Je = 0 (Cauchy, times Je); the wall
    force is FEBio's Cauchy stress sigma_xx = (mu (1/g^2 - 1) + lam ln Je) / Je on the current
    face t^2."""
    E, nu = 1e4, 0.3
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    growth = '<growth type="fiber growth"><multiplier lc="1">1</multiplier></growth>'
    for (stretch, forces), g in zip(_run(_deck(tmp_path, growth, WALL)), (1.2, 1.4), strict=True):
        t = brentq(lambda t, g=g: mu * (t * t - 1) + lam * np.log(t * t / g), 0.5, 2.0, xtol=1e-15)
        np.testing.assert_allclose(stretch, [1.0, t, t], rtol=1e-7)
        Je = t * t / g
        sigma = (mu * (1 / g**2 - 1) + lam * np.log(Je)) / Je
        assert sigma < 0.0  # the cube pushes on the walls
        assert forces["wall"][0] == pytest.approx(sigma * t * t, rel=1e-6)


def test_refusals(tmp_path):
    bad = '<growth type="twist growth"><multiplier>1</multiplier></growth>'
    with pytest.raises(FebError, match=r"growth.feb:\d+ <growth>: growth type 'twist growth'"):
        read_feb(_deck(tmp_path, bad))
    bad = '<growth type="volume growth"><iso>1</iso></growth>'
    with pytest.raises(FebError, match=r"growth.feb:\d+ <iso>: parameter 'iso'"):
        read_feb(_deck(tmp_path, bad))
    bad = '<growth type="fiber growth"><fiber type="local">1,2</fiber></growth>'
    with pytest.raises(FebError, match=r"growth.feb:\d+ <fiber>: .*\"vector\" and \"angles\""):
        read_feb(_deck(tmp_path, bad))
    with pytest.raises(FebError, match=r"growth.feb:\d+ <material>: .*needs an <elastic>"):
        read_feb(_deck(tmp_path, ""))
