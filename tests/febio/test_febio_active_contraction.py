"""FEBio's prescribed active contraction read from decks of our own: a cube held on its three
symmetry planes, free elsewhere, whose mixture's active stress T0 follows a load curve; its
stretches against the closed forms (neo-Hookean + uniaxial contraction along the mat_axis
"angles" direction; Mooney-Rivlin + uncoupled isotropic contraction, a pure dilation), and the
refusals, each one line naming the XML element and its line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import fsolve

from tissuesim.febio import FebError, febio_scene, load_febio, read_feb

DECK = """<?xml version="1.0" encoding="ISO-8859-1"?>
<febio_spec version="4.0">
  <Module type="solid"/>
  <Control>
    <analysis>STATIC</analysis>
    <time_steps>2</time_steps>
    <step_size>0.5</step_size>
  </Control>
  <Material>
    <material id="1" name="tissue" type="{mixture}">
{material}
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
  </Boundary>
  <LoadData>
    <load_controller id="1" type="loadcurve">
      <interpolate>LINEAR</interpolate>
      <points><pt>0,0</pt><pt>1,1</pt></points>
    </load_controller>
  </LoadData>
</febio_spec>
"""

UNIAXIAL = """      <solid type="neo-Hookean"><E>10000</E><v>0.3</v></solid>
      <solid type="prescribed uniaxial active contraction">
        <T0 lc="1">2000</T0>
        <mat_axis type="angles"><theta>90</theta><phi>90</phi></mat_axis>
      </solid>"""

ISOTROPIC_UC = """      <k>20000</k>
      <solid type="Mooney-Rivlin"><c1>1000</c1><c2>300</c2></solid>
      <solid type="uncoupled prescribed isotropic active contraction">
        <T0 lc="1">1500</T0>
      </solid>"""


def _deck(tmp_path: Path, material: str, mixture: str = "solid mixture") -> Path:
    path = tmp_path / "active.feb"
    path.write_text(DECK.format(material=material, mixture=mixture))
    return path


def _stretches(path: Path) -> list[np.ndarray]:
    """The cube's stretches (x, y, z) after each of the two steps (t = 0.5, 1)."""
    sim = load_febio(path).simulation
    out = []
    for _ in range(2):
        sim.step()
        X, x = sim.body("body").mesh.points, sim.body_positions("body")
        out.append(np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)]))
    return out


def test_uniaxial_contraction_along_the_angles_axis(tmp_path):
    """theta = phi = 90 degrees: n0 = y. By hand, the neo-Hookean's second Piola-Kirchhoff
    stress mu (1 - 1/l^2) + lam ln J / l^2 plus T0 along y, zero across (stretch t), with
    T0 = 2000 * t_run (the load curve): at t = 0.5 and 1."""
    E, nu = 1e4, 0.3
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))

    def closed_form(T0: float) -> np.ndarray:
        def eqs(v):
            l, t = v
            J = l * t * t
            return [mu * (1 - 1 / l**2) + lam * np.log(J) / l**2 + T0,
                    mu * (1 - 1 / t**2) + lam * np.log(J) / t**2]  # fmt: skip

        l, t = fsolve(eqs, [0.9, 1.0], xtol=1e-12)
        return np.array([t, l, t])

    got = _stretches(_deck(tmp_path, UNIAXIAL))
    for stretch, T0 in zip(got, (1000.0, 2000.0), strict=True):
        np.testing.assert_allclose(stretch, closed_form(T0), rtol=1e-8)
    assert got[1][1] < got[0][1] < 1.0 < got[1][0]  # shortens along the fibre, swells across


def test_uncoupled_isotropic_contraction_is_a_dilation(tmp_path):
    """Mooney-Rivlin (no deviatoric stress in a dilation) + S = T0 I in an uncoupled mixture
    with k: the stretch s solves k 3 ln s / s^2 = -T0 (U = k/2 ln(J)^2, FEBio's default)."""
    k = 20000.0
    got = _stretches(_deck(tmp_path, ISOTROPIC_UC, "uncoupled solid mixture"))
    for stretch, T0 in zip(got, (750.0, 1500.0), strict=True):
        (s,) = fsolve(lambda s, T0=T0: k * 3 * np.log(s) / s**2 + T0, [0.95], xtol=1e-12)
        np.testing.assert_allclose(stretch, [s, s, s], rtol=1e-8)


def test_mat_axis_angles_are_febios_spherical_axes(tmp_path):
    """FEBio's FEMat3dSphericalAngleMap: e1 = (cos theta sin phi, sin theta sin phi, cos phi),
    the trans iso contraction's n0."""
    the, phi = np.radians(30.0), np.radians(60.0)
    deck = UNIAXIAL.replace("<theta>90</theta><phi>90</phi>", "<theta>30</theta><phi>60</phi>")
    deck = deck.replace("prescribed uniaxial", "prescribed trans iso")
    data, _ = febio_scene(read_feb(_deck(tmp_path, deck)), "x")
    fiber = data["material"]["components"][1]["fiber"]
    want = [np.cos(the) * np.sin(phi), np.sin(the) * np.sin(phi), np.cos(phi)]
    np.testing.assert_allclose(fiber, want, atol=1e-14)
    assert data["material"]["components"][1]["T0"].startswith("2000.0 * (")


def test_refusals(tmp_path):
    alone = """      <solid type="neo-Hookean"><E>1</E><v>0.3</v></solid>"""
    path = tmp_path / "alone.feb"
    text = DECK.format(material=alone, mixture="solid mixture").replace(
        '<material id="1" name="tissue" type="solid mixture">\n'
        '      <solid type="neo-Hookean"><E>1</E><v>0.3</v></solid>',
        '<material id="1" name="tissue" type="prescribed isotropic active contraction">\n'
        "      <T0>1</T0>",
    )
    path.write_text(text)
    with pytest.raises(FebError, match=r"alone.feb:\d+ <material>: .*mixture's <solid> only"):
        read_feb(path)
    with pytest.raises(FebError, match=r"active.feb:\d+ <T0>: load curve 7 is used but not"):
        load_febio(_deck(tmp_path, UNIAXIAL.replace('lc="1"', 'lc="7"')))
    with pytest.raises(FebError, match=r"active.feb:\d+ <psi>: .*angles.*<theta> and <phi>"):
        read_feb(_deck(tmp_path, UNIAXIAL.replace("<theta>90</theta>", "<psi>90</psi>")))
    with pytest.raises(FebError, match=r"active.feb:\d+ <E>: .*curve"):
        read_feb(_deck(tmp_path, UNIAXIAL.replace("<E>10000</E>", '<E lc="1">10000</E>')))


def test_laws_without_an_energy_are_refused_with_the_reason(tmp_path):
    """FEBio's Newtonian viscous solid (its stress from the rate (F - Fp) F^-1 / dt) and the
    active fibre contraction of a trans iso law have no energy of F: one line each says so."""
    viscous = UNIAXIAL.replace(
        """      <solid type="prescribed uniaxial active contraction">
        <T0 lc="1">2000</T0>
        <mat_axis type="angles"><theta>90</theta><phi>90</phi></mat_axis>
      </solid>""",
        '      <solid type="Newtonian viscous solid"><mu>1</mu><kappa>1</kappa></solid>',
    )
    with pytest.raises(FebError, match=r"active.feb:\d+ <solid>: .*Newtonian viscous solid.*"
                       "not the derivative of an energy"):  # fmt: skip
        read_feb(_deck(tmp_path, viscous))
    text = DECK.format(material="", mixture="solid mixture").replace(
        '<material id="1" name="tissue" type="solid mixture">',
        '<material id="1" name="tissue" type="trans iso Mooney-Rivlin">\n'
        "      <c1>1</c1><c2>0</c2><c3>1</c3><c4>1</c4><c5>1</c5><lam_max>10</lam_max><k>100</k>\n"
        '      <active_contraction><ascl lc="1">1</ascl><Tmax>1</Tmax></active_contraction>',
    )
    path = tmp_path / "fibre.feb"
    path.write_text(text)
    with pytest.raises(FebError, match=r"fibre.feb:\d+ <active_contraction>: .*energy"):
        read_feb(path)
