"""FEBio's continuous fibre distribution read from a .feb (tests/febio/models/cfd_uniaxial.feb:
a solid mixture of neo-Hookean, a von-Mises-3d distribution of fiber-exp-pow summed by the
adaptive fibers-3d-gkt, and an elliptical one in the x-y plane by fibers-2d-trapezoidal):
the cube pulled along x reaches the homogeneous state whose lateral stresses are zero and whose
pull is the law's P_xx (the law itself checked against finite differences and SciPy's quad in
tests/materials/test_continuous_fibre_distribution.py); the tables read; the refusals, each
one line naming the XML element and its line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tissuesim.febio import FebError, febio_scene, load_febio, read_feb
from tissuesim.materials import make_material

MODELS = Path(__file__).parent / "models"


def test_cfd_mixture_pull_is_the_laws_stress():
    data, _ = febio_scene(read_feb(MODELS / "cfd_uniaxial.feb"), "x")
    table = dict(data["material"])
    law = make_material(table.pop("model"), **table)
    sim = load_febio(MODELS / "cfd_uniaxial.feb").simulation
    for _ in range(3):
        sim.step()
    X, x = sim.body("body").mesh.points, sim.body_positions("body")
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    force = abs(sim.step().extra["forces"]["pull"][0])
    P = law.stress(np.diag(stretch)[None])[0]
    assert stretch[0] == pytest.approx(1.15)
    assert stretch[1] != pytest.approx(stretch[2], rel=1e-4)  # the x-y fibres pull in y too
    np.testing.assert_allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)
    nh = make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    assert force > 1.2 * nh.stress(np.diag(stretch)[None])[0, 0, 0]  # the fibres pull


def test_cfd_tables_are_read():
    data, _ = febio_scene(read_feb(MODELS / "cfd_uniaxial.feb"), "x")
    nh, cfd, planar = data["material"]["components"]
    assert cfd["model"] == "continuous fiber distribution"
    assert cfd["fibers"] == {"model": "fiber-exp-pow", "alpha": 2.0, "beta": 2.5,
                             "ksi": 5000.0, "mu": 0.0, "lam0": 1.0}  # fmt: skip
    assert cfd["distribution"] == {"model": "von-Mises-3d", "b": 3.0}
    assert cfd["scheme"] == {"model": "fibers-3d-gkt", "nph": 11.0, "nth": 31.0}
    np.testing.assert_allclose(planar["mat_axis_a"], [1, 0, 0])
    np.testing.assert_allclose(planar["mat_axis_d"], [0, 1, 0])
    assert planar["distribution"] == {"model": "elliptical", "spa1": 4.0, "spa2": 1.0}


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ('<scheme type="fibers-2d-trapezoidal">', '<scheme type="fibers-3d-fei">',
         r"cfd\.feb:\d+ <material>: .*fibers_3d_fei.*fibers-3d-fei"),
        ("<spa2>1</spa2>", "<spa2>1</spa2><b>2</b>", r"<material>: .*unknown parameter 'b'"),
        ('<distribution type="elliptical">', "<distribution>",
         r"cfd\.feb:\d+ <distribution>: <distribution> needs its type"),
        ("<b>3</b>", '<b lc="1">3</b>', r"cfd\.feb:\d+ <b>: .*field, a curve or a table"),
        ("<a>1,0,0</a>", "<a>1,1,0</a>",
         r"cfd\.feb:\d+ <solid>: a continuous fiber distribution with fibers-3d-gkt under a "
         r"mat_axis other than the global axes"),
    ],
)  # fmt: skip
def test_cfd_refusals_name_the_element_and_line(tmp_path, old, new, match):
    text = (MODELS / "cfd_uniaxial.feb").read_text()
    assert old in text
    path = tmp_path / "cfd.feb"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(FebError, match=match):
        febio_scene(read_feb(path), "x")


def test_2d_trans_iso_mooney_rivlin_pull_is_the_laws_stress():
    """FEBio's 2D trans iso Mooney-Rivlin (tests/febio/models/trans_iso_2d_uniaxial.feb: fibres
    in the x-y plane, normal to the axis z, weighted by the ellipse w = (3, 1)) pulled along x,
    hex8 with FEBio's three-field element: the homogeneous state's lateral stresses are zero and
    its pull is the law's P_xx; the fibres stiffen x more than y (y shortens more than z)."""
    data, _ = febio_scene(read_feb(MODELS / "trans_iso_2d_uniaxial.feb"), "x")
    assert data["simulation"]["formulation"] == "mean_dilatation"
    table = dict(data["material"])
    assert table["w"] == [3.0, 1.0] and table["fiber"] == [0.0, 0.0, 1.0]
    law = make_material(table.pop("model"), **table)
    sim = load_febio(MODELS / "trans_iso_2d_uniaxial.feb").simulation
    for _ in range(3):
        sim.step()
    X, x = sim.body("body").mesh.points, sim.body_positions("body")
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    force = abs(sim.step().extra["forces"]["pull"][0])
    P = law.stress(np.diag(stretch)[None])[0]
    assert stretch[0] == pytest.approx(1.15)
    np.testing.assert_allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)
    assert stretch[1] < stretch[2] - 1e-3


def test_mooney_rivlin_von_mises_fibers_pull_is_the_laws_stress():
    """FEBio's Mooney-Rivlin von Mises Fibers (tests/febio/models/mr_von_mises_uniaxial.feb:
    fibres in the x-y plane around x, kf = 5, the constrained density) pulled along x, hex8
    with FEBio's three-field element: lateral stresses zero, the pull the law's P_xx, y
    shortened more than z (the fibres near x also pull in y)."""
    data, _ = febio_scene(read_feb(MODELS / "mr_von_mises_uniaxial.feb"), "x")
    assert data["simulation"]["formulation"] == "mean_dilatation"
    table = dict(data["material"])
    assert table["gipt"] == 20.0 and table["vmc"] == 2.0
    law = make_material(table.pop("model"), **table)
    sim = load_febio(MODELS / "mr_von_mises_uniaxial.feb").simulation
    for _ in range(3):
        sim.step()
    X, x = sim.body("body").mesh.points, sim.body_positions("body")
    stretch = np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])
    force = abs(sim.step().extra["forces"]["pull"][0])
    P = law.stress(np.diag(stretch)[None])[0]
    assert stretch[0] == pytest.approx(1.15)
    np.testing.assert_allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)
    assert stretch[1] < stretch[2] - 1e-3
