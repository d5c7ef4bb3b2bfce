"""FEBio's laws added for its verification suite (issue 42): finite differences of stress and
tangent in 2D and 3D, the rest state, objectivity, anisotropy where the law has it, the way back
from ``parameters()``, the mean-dilatation volumetric part, and the parameter refusals."""

from __future__ import annotations

import numpy as np
import pytest
from stress_differences import central_difference, random_deformations, relative_difference

from tissuesim.errors import MaterialError
from tissuesim.materials import make_material
from tissuesim.materials.volumetric import volumetric_part

TIVW = dict(c1=200.0, c2=1.5, c3=10.0, c4=5.0, c5=400.0, lam_max=1.1, k=5000.0)
#: name -> (registry name, parameters, FEBio type, isotropic)
LAWS = {
    "tivw": ("trans_iso_veronda_westmann", {**TIVW, "fiber": [1, 1, 0]},
             "trans iso Veronda-Westmann", False),
    "tivw_goh": ("trans_iso_veronda_westmann",
                 {**TIVW, "fiber": [0.2, 1, 0.5], "pressure_model": "Abaqus (GOH)"},
                 "trans iso Veronda-Westmann", False),
}  # fmt: skip


def _law(key: str):
    name, params, _, _ = LAWS[key]
    return make_material(name, **params)


@pytest.mark.parametrize("key", sorted(LAWS))
@pytest.mark.parametrize("d", [2, 3])
def test_stress_and_tangent_match_finite_differences(key, d):
    law = _law(key)
    F = random_deformations(np.random.default_rng(d), 8, d, 0.25)
    res = law.evaluate(F)
    assert relative_difference(res.stress, central_difference(law.energy_density, F, 1e-6)) < 1e-7
    assert relative_difference(res.tangent, central_difference(law.stress, F, 1e-6)) < 1e-7
    At = np.transpose(res.tangent, (0, 3, 4, 1, 2))
    np.testing.assert_allclose(res.tangent, At, atol=1e-12 * np.abs(At).max())


@pytest.mark.parametrize("key", sorted(LAWS))
def test_rest_state_objectivity_and_anisotropy(key):
    law = _law(key)
    res = law.evaluate(np.eye(3)[None])
    assert abs(res.energy[0]) < 1e-12 * law.mu and np.abs(res.stress).max() < 1e-12 * law.mu
    rng = np.random.default_rng(4)
    F = random_deformations(rng, 6, 3, 0.3)
    Q, _ = np.linalg.qr(rng.standard_normal((6, 3, 3)))
    Q[np.linalg.det(Q) < 0, :, 0] *= -1
    psi = law.energy_density(F)
    np.testing.assert_allclose(law.energy_density(Q @ F), psi, rtol=1e-11)
    scale = np.abs(law.stress(F)).max()
    np.testing.assert_allclose(law.stress(Q @ F), Q @ law.stress(F), rtol=1e-9, atol=1e-11 * scale)
    turned = np.max(np.abs(law.energy_density(F @ Q) - psi) / np.abs(psi))
    assert turned < 1e-10 if LAWS[key][3] else turned > 1e-3


@pytest.mark.parametrize("key", sorted(LAWS))
def test_by_febio_name_and_back_from_its_parameters(key):
    name, params, febio, _ = LAWS[key]
    law = make_material(febio, **params)
    assert law.name == name and law.febio_name == febio
    again = make_material(name, **law.parameters())
    F = random_deformations(np.random.default_rng(7), 4, 3, 0.3)
    np.testing.assert_allclose(again.stress_derivative(F), law.stress_derivative(F), rtol=1e-14)


@pytest.mark.parametrize("key", sorted(LAWS))
def test_volumetric_part_is_the_bulk_term(key):
    """The mean-dilatation split of an uncoupled law: U(J) is its bulk term (k, pressure model),
    and psi - U(J) is zero under a pure dilatation (the deviatoric part does not see J)."""
    law = _law(key)
    part = volumetric_part(law)
    assert (part.theta_kind, part.u_kind, part.lam) == ("J", law.bulk_kind, law.k)
    F = np.eye(3)[None] * np.array([0.9, 1.0 + 1e-3, 1.2])[:, None, None]
    U = part.energy(np.linalg.det(F), 0)[0]
    np.testing.assert_allclose(law.energy_density(F), U, rtol=1e-12, atol=1e-12 * law.k)
    assert U[0] > 0.0 and U[2] > 0.0


def test_trans_iso_veronda_westmann_without_fibre_is_veronda_westmann():
    F = random_deformations(np.random.default_rng(9), 6, 3, 0.3)
    ti = make_material("trans_iso_veronda_westmann", c1=200.0, c2=1.5, k=5000.0)
    vw = make_material("veronda_westmann", c1=200.0, c2=1.5, k=5000.0)
    np.testing.assert_allclose(ti.stress_derivative(F), vw.stress_derivative(F), rtol=1e-11)
    # the fibre bears tension only: compressed along it, the law is the matrix
    fibre = make_material("trans_iso_veronda_westmann", **TIVW)
    G = np.diag([0.9, 1.05, 1.05])[None]
    np.testing.assert_allclose(fibre.stress(G), ti.stress(G), rtol=1e-12)
    assert (
        fibre.stress(np.diag([1.1, 0.95, 0.95])[None])[0, 0, 0]
        > ti.stress(np.diag([1.1, 0.95, 0.95])[None])[0, 0, 0] + 1.0
    )


@pytest.mark.parametrize(
    "params, message",
    [({"c2": 1.0, "k": 1.0}, "needs c1"), ({**TIVW, "c2": 0.0}, "c2 must be > 0"),
     ({**TIVW, "c4": -1.0}, "c3, c4, c5 must be >= 0"), ({**TIVW, "k": None}, "needs k")],
)  # fmt: skip
def test_trans_iso_veronda_westmann_refusals(params, message):
    with pytest.raises(MaterialError, match=message):
        make_material("trans_iso_veronda_westmann", **params)
