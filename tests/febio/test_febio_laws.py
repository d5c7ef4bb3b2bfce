"""FEBio's material laws added for its verification suite (issue 42), each through a small
model of tests/febio/models read by ``load_febio``: the homogeneous state against the law, and
the fibre directions FEBio's ``<fiber type="local">`` and ``type="user"`` give."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tissuesim.febio import FebError, febio_scene, load_febio, read_feb

MODELS = Path(__file__).parent / "models"


def _run(scene, steps: int) -> np.ndarray:
    sim = scene.simulation
    for _ in range(steps):
        sim.step()
    return sim.body_positions("body")


def _stretches(scene, x: np.ndarray) -> np.ndarray:
    X = scene.simulation.body("body").mesh.points
    return np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])


def test_trans_iso_veronda_westmann_uniaxial_is_the_laws_homogeneous_state():
    """The cube pulled 1.15 along its fibre (type="local", nodes 1 -> 2: x) stretches
    homogeneously, contracts equally across it (transversely isotropic), and its pull is the
    law's P_xx with the lateral stresses zero; the fibre more than doubles it here."""
    from tissuesim.materials import TransIsoVerondaWestmann

    scene = load_febio(MODELS / "tivw_uniaxial.feb")
    x = _run(scene, 3)
    stretch = _stretches(scene, x)
    params = dict(c1=2000.0, c2=1.5, c3=500.0, c4=20.0, c5=60000.0, lam_max=1.1, k=1e6)
    P = TransIsoVerondaWestmann(**params).evaluate(np.diag(stretch)[None], 1).stress[0]
    force = abs(scene.simulation.step().extra["forces"]["pull"][0])  # held: the same state
    assert stretch[0] == pytest.approx(1.15)
    assert stretch[1] == pytest.approx(stretch[2], rel=1e-9) and stretch[1] < 0.95
    assert np.allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)
    matrix = TransIsoVerondaWestmann(**{**params, "c3": 0.0, "c5": 0.0})
    assert P[0, 0] > 2.0 * matrix.evaluate(np.diag(stretch)[None], 1).stress[0, 0, 0]


def _with(tmp_path: Path, name: str, old: str, new: str) -> Path:
    text = (MODELS / f"{name}.feb").read_text()
    assert old in text
    path = tmp_path / f"{name}.feb"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize(
    "nodes, expected", [("1,2", [1, 0, 0]), ("1,4", [0, 1, 0]), ("2,7", [0, 1, 1]), ("", [1, 0, 0])]
)
def test_fiber_type_local_is_the_element_edge(tmp_path, nodes, expected):
    """FEBio's FELocalVectorGenerator: the unit vector from element node n1 to n2 at rest
    (default 1, 2)."""
    path = _with(tmp_path, "tivw_uniaxial", "<local>1,2</local>", f"<local>{nodes}</local>")
    data, _ = febio_scene(read_feb(path), "x")
    np.testing.assert_allclose(
        data["material"]["fiber"], np.array(expected) / np.linalg.norm(expected)
    )


def test_fiber_type_user_takes_the_element_data_and_needs_it_everywhere(tmp_path):
    user = '<fiber type="user"/>'
    old = '<fiber type="local">\n        <local>1,2</local>\n      </fiber>'
    path = _with(tmp_path, "tivw_uniaxial", old, user)
    with pytest.raises(
        FebError, match=r"fiber type 'user': every element .* <ElementData type=\"fiber\">"
    ):
        febio_scene(read_feb(path), "x")
    data = (
        '<MeshData>\n    <ElementData type="fiber" elem_set="cube">\n'
        '      <e lid="1">0,0,2</e>\n    </ElementData>\n  </MeshData>\n  <Boundary>'
    )
    path.write_text(path.read_text().replace("<Boundary>", data, 1))
    scene_data, _ = febio_scene(read_feb(path), "x")
    fiber = np.array(scene_data["material"]["fiber"])
    np.testing.assert_allclose(fiber / np.linalg.norm(fiber), [0.0, 0.0, 1.0])


@pytest.mark.parametrize(
    "local, message",
    [("1,1", "two different element nodes"), ("1,9", "the elements have 8 nodes"),
     ("1,2,3", "two element nodes")],
)  # fmt: skip
def test_fiber_type_local_refusals(tmp_path, local, message):
    path = _with(tmp_path, "tivw_uniaxial", "<local>1,2</local>", f"<local>{local}</local>")
    with pytest.raises(FebError, match=message):
        febio_scene(read_feb(path), "x")


ORTHO = dict(E1=1000.0, E2=2000.0, E3=3000.0, G12=600.0, G23=400.0, G31=500.0)
ORTHO.update(v12=0.3, v23=0.2, v31=0.25, mat_axis_a=[0, 1, 0], mat_axis_d=[-1, 0, 0])


@pytest.mark.parametrize(
    "name, law, extra",
    [("orthotropic_uniaxial", "orthotropic_elastic", {}),
     ("fung_orthotropic_uniaxial", "fung_orthotropic", {"c": 1500.0, "k": 20000.0}),
     ("fung_ortho_compressible_uniaxial", "fung_ortho_compressible", {"c": 1500.0, "k": 20000.0})],
)  # fmt: skip
def test_orthotropic_uniaxial_is_the_laws_homogeneous_state(name, law, extra):
    """The cube pulled 1.15 along x = -a_2 (mat_axis a = y, d = -x) stretches homogeneously,
    contracts differently along y (a_1, E1 = 1000) and z (a_3, E3 = 3000), and its pull is
    the law's P_xx with the lateral stresses zero."""
    from tissuesim.materials import make_material

    scene = load_febio(MODELS / f"{name}.feb")
    x = _run(scene, 3)
    stretch = _stretches(scene, x)
    P = make_material(law, **ORTHO, **extra).evaluate(np.diag(stretch)[None], 1).stress[0]
    force = abs(scene.simulation.step().extra["forces"]["pull"][0])
    assert stretch[0] == pytest.approx(1.15)
    assert abs(stretch[1] - stretch[2]) > 1e-3
    assert np.allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)


@pytest.mark.parametrize(
    "name, law, params",
    [("holmes_mow_uniaxial", "holmes_mow", {"E": 1000.0, "v": 0.3, "beta": 0.5}),
     ("uncoupled_holmes_mow_uniaxial", "uncoupled_holmes_mow",
      {"mu": 300.0, "beta": 2.0, "k": 5000.0}),
     ("arruda_boyce_unconstrained_uniaxial", "arruda_boyce_unconstrained",
      {"ksi": 1000.0, "N": 4.0, "n_term": 30, "kappa": 5000.0}),
     ("isotropic_hencky_uniaxial", "isotropic_hencky", {"E": 1000.0, "v": 0.3})],
)  # fmt: skip
def test_isotropic_uniaxial_is_the_laws_homogeneous_state(name, law, params):
    """The cube pulled 1.15 along x stretches homogeneously, contracts equally along y and z
    (isotropic), and its pull is the law's P_xx with the lateral stresses zero."""
    from tissuesim.materials import make_material

    scene = load_febio(MODELS / f"{name}.feb")
    x = _run(scene, 3)
    stretch = _stretches(scene, x)
    P = make_material(law, **params).evaluate(np.diag(stretch)[None], 1).stress[0]
    force = abs(scene.simulation.step().extra["forces"]["pull"][0])
    assert stretch[0] == pytest.approx(1.15)
    assert stretch[1] == pytest.approx(stretch[2], rel=1e-9) and stretch[1] < 0.99
    assert np.allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)


def test_coupled_trans_iso_mooney_rivlin_uniaxial_is_the_laws_homogeneous_state():
    """The cube pulled 1.15 along its fibre (x): homogeneous, equal lateral contraction, the
    pull the law's P_xx with the lateral stresses zero."""
    from tissuesim.materials import CoupledTransIsoMooneyRivlin

    scene = load_febio(MODELS / "coupled_trans_iso_uniaxial.feb")
    x = _run(scene, 3)
    stretch = _stretches(scene, x)
    params = dict(c1=1000.0, c2=200.0, c3=500.0, c4=20.0, c5=60000.0, lam_max=1.1, k=20000.0)
    P = CoupledTransIsoMooneyRivlin(**params).evaluate(np.diag(stretch)[None], 1).stress[0]
    force = abs(scene.simulation.step().extra["forces"]["pull"][0])
    assert stretch[0] == pytest.approx(1.15)
    assert stretch[1] == pytest.approx(stretch[2], rel=1e-9) and stretch[1] < 0.99
    assert np.allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)


def test_tc_nonlinear_orthotropic_uniaxial_is_the_laws_homogeneous_state(tmp_path):
    """mat_axis a = y, d = -x: the pull along x stretches family a_2 (beta 3, ksi 3000); the
    cube deforms homogeneously, y and z contract differently (a_1 and a_3 slack but the state
    is not transversely isotropic: the pull's family differs), and the pull is P_xx. beta and
    ksi are read as three values, or one for all three axes."""
    from tissuesim.materials import TCNonlinearOrthotropic

    scene = load_febio(MODELS / "tc_nonlinear_orthotropic_uniaxial.feb")
    x = _run(scene, 3)
    stretch = _stretches(scene, x)
    params = dict(c1=1000.0, c2=200.0, beta=[2.5, 3, 4], ksi=[8000, 3000, 5000], k=50000.0)
    law = TCNonlinearOrthotropic(**params, mat_axis_a=[0, 1, 0], mat_axis_d=[-1, 0, 0])
    P = law.evaluate(np.diag(stretch)[None], 1).stress[0]
    force = abs(scene.simulation.step().extra["forces"]["pull"][0])
    assert stretch[0] == pytest.approx(1.15)
    assert np.allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert force == pytest.approx(P[0, 0], rel=1e-6)
    path = _with(
        tmp_path, "tc_nonlinear_orthotropic_uniaxial", "<beta>2.5,3,4</beta>", "<beta>3</beta>"
    )
    data, _ = febio_scene(read_feb(path), "x")
    assert data["material"]["beta"] == [3.0] and data["material"]["ksi"] == [8000, 3000, 5000]


def test_hyperelastic_w_is_the_energy_law_and_runs_as_neo_hookean(tmp_path):
    """FEBio's hyperelastic with W the neo-Hookean energy: the energy law with the assigned
    parameters, whose run is the neo-Hookean model's to round-off."""
    scene = load_febio(MODELS / "hyperelastic_uniaxial.feb")
    data, _ = febio_scene(read_feb(MODELS / "hyperelastic_uniaxial.feb"), "x")
    material = data["material"]
    assert (material["model"], material["mu"], material["lam"]) == ("energy", 1000.0, 4000.0)
    assert material["psi"] == "mu*((I1 - 3)/2 - ln(J)) + lam*ln(J)*ln(J)/2"
    x = _run(scene, 3)
    E, nu = 1000.0 * (3 * 4000.0 + 2 * 1000.0) / (4000.0 + 1000.0), 4000.0 / (2 * 5000.0)
    text = (MODELS / "hyperelastic_uniaxial.feb").read_text()
    old = text[text.index('<material id="1"') : text.index("</material>")]
    new = '<material id="1" name="tissue" type="neo-Hookean"><density>1000</density>'
    new += f"<E>{E!r}</E><v>{nu!r}</v>"
    path = tmp_path / "neo.feb"
    path.write_text(text.replace(old, new))
    np.testing.assert_allclose(x, _run(load_febio(path), 3), atol=1e-9)


@pytest.mark.parametrize(
    "w, extra, expected",
    [("c1 = 1; c2 = 0.1; c1*(I1 - 3) + c2*(I2 - 3)", "<k>100</k>",
      "c1*(I1b - 3) + c2*(I2b - 3) + k/2*ln(J)**2"),
     ("c1 = 2; c1*(I1 - 3)", "<k>100</k><pressure_model>Abaqus</pressure_model>",
      "c1*(I1b - 3) + k/2*(J - 1)**2"),
     ("e = 2; e*(exp(I1 - 3) - 1) + 1e-3*log(I2/3)", "<k>5</k>",
      "p_e*(exp(I1b - 3) - 1) + 1e-3*0.4342944819032518*ln(I2b/3) + k/2*ln(J)**2")],
)  # fmt: skip
def test_uncoupled_hyperelastic_w_in_the_deviatoric_invariants(tmp_path, w, extra, expected):
    """I1, I2 become I1b, I2b, FEBio's bulk term of k and pressure_model is added, FEBio's log
    is decimal, a parameter named like a tissuesim name is renamed; with W Mooney-Rivlin's it
    is the uncoupled Mooney-Rivlin law."""
    from tissuesim.materials import make_material

    text = (MODELS / "hyperelastic_uniaxial.feb").read_text()
    old = text[text.index('<material id="1"') : text.index("</material>")]
    new = f'<material id="1" name="tissue" type="uncoupled hyperelastic"><W>{w}</W>{extra}'
    path = tmp_path / "uc.feb"
    path.write_text(text.replace(old, new))
    model = read_feb(path)
    assert any("three-field element" in n for n in model.notes)
    data, _ = febio_scene(model, "x")
    params = dict(data["material"])
    assert params.pop("model") == "energy" and params.pop("psi") == expected
    if "c2" in params:
        law = make_material("energy", psi=expected, **params)
        mr = make_material("mooney_rivlin", c1=1.0, c2=0.1, k=100.0)
        F = np.array([[[1.2, 0.1, 0.0], [0.05, 0.9, 0.1], [0.0, -0.1, 1.05]]])
        np.testing.assert_allclose(law.stress_derivative(F), mr.stress_derivative(F), rtol=1e-10)


@pytest.mark.parametrize(
    "kind, w, message",
    [("hyperelastic", "mu = 1; mu*(I1 - 3)/2 - mu*ln(J) + X", "the position X"),
     ("hyperelastic", "mu = 1; nu*(I1 - 3)", "unknown name 'nu'"),
     ("hyperelastic", "mu = one; mu*(I1 - 3)", "a parameter is a number"),
     ("hyperelastic", "mu = 1; mu*(I1 - 3)", "not stress-free at rest"),
     ("uncoupled hyperelastic", "mu = 1; mu*(I1 - 3) + J", "unknown name J"),
     ("uncoupled hyperelastic", "mu = 1; mu*(I1 - 3)", "needs its bulk modulus <k>")],
)  # fmt: skip
def test_hyperelastic_refusals(tmp_path, kind, w, message):
    text = (MODELS / "hyperelastic_uniaxial.feb").read_text()
    old = text[text.index('<material id="1"') : text.index("</material>")]
    path = tmp_path / "bad.feb"
    path.write_text(text.replace(old, f'<material id="1" name="t" type="{kind}"><W>{w}</W>'))
    with pytest.raises(FebError, match=message):
        read_feb(path)
